// The sliced model's exact propagation over each output interval at a constant speed as affine
// maps (docs/model.md "Back to one product per sample at the nominal speed").
#pragma once

#include <vector>

#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"

namespace drivetrain_stiffness {

class SlicedIntervalMaps {
 public:
  using AffineMap = SlicedModalPropagator::AffineMap;
  /// `intervals` per mesh period (>= 1) at mesh frequency f > 0 [Hz] over `slices`. Throws
  /// InvalidInput otherwise.
  SlicedIntervalMaps(const SlicedMesh& slices, int intervals, double f);

  /// Every interval is made again when next used.
  void invalidate();
  int intervals() const { return static_cast<int>(intervals_.size()); }
  double meshFrequency() const { return f_; }

  /// Interval i's end boundary (0: its start).
  int boundaries(int i) const {
    return static_cast<int>(intervals_[static_cast<std::size_t>(i)].offset.size()) - 1;
  }
  /// Boundary m's phase from interval i's start [turns].
  double offset(int i, int m) const {
    return intervals_[static_cast<std::size_t>(i)].offset[static_cast<std::size_t>(m)];
  }
  /// The last boundary at or before phase offset u [turns] (0 for u <= 0).
  int boundaryAtOrBefore(int i, double u) const;

  /// y from boundary m of interval i to its end, drive force [N] held; false, untouched, where
  /// the maps are not made or not usable.
  bool toEnd(const SlicedModalPropagator& exact, int i, int m, State6& y, double drive_force);
  /// Interval i's maps ready, made now on its kUsesBeforeMaking-th call.
  bool available(const SlicedModalPropagator& exact, int i);
  /// y from interval i's start to its boundary m.
  bool fromStart(const SlicedModalPropagator& exact, int i, int m, State6& y, double drive_force);
  long intervalsMade() const { return made_; }
  static constexpr int kUsesBeforeMaking = 2;

 private:
  struct Interval {
    std::vector<double> offset;
    std::vector<int> slice;
    std::vector<AffineMap> head;  ///< start -> boundary m
    std::vector<AffineMap> tail;  ///< boundary m -> end
    int uses = 0;
    bool ready = false, usable = false;
  };

  bool make(const SlicedModalPropagator& exact, int i);
  std::vector<Interval> intervals_;
  double f_;
  long made_ = 0;
  AffineMap piece_;
};

}  // namespace drivetrain_stiffness

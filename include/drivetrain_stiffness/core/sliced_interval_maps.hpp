// The sliced model's exact propagation over the output intervals of one mesh period at one constant
// speed, as affine maps: the nominal phase after a bearing-stiffness or damping change
// (docs/model.md, "Back to one product per sample at the nominal speed").
//
// At the nominal speed the output grid holds a whole number n of samples per mesh period, so the
// interval from sample k to k + 1 always spans the same mesh phases, [i/n, (i+1)/n] with i = k mod
// n. With the contacts in the loaded regime the sliced model is linear there, and its exact
// solution over the interval (the product of the slices' exact maps,
// SlicedModalPropagator::loadedSliceMap) is one affine map, y -> Phi y + d F_d + c: a 6x6 product
// per sample instead of crossing the ~86 slices of an interval one by one (at 1000 rpm and 1 kHz).
// The maps are products of the slices' exact maps, so they hold the sliced model's solution to
// rounding (1e-12 of the slice-by-slice propagation:
// SlicedIntervalMaps.AreTheSliceBySliceSolutionAsAMatrix). For inputs stamped inside an interval
// each slice boundary b inside it keeps the map from the interval's start to b (head) and from b to
// its end (tail): a stretch from an input's stamp to the interval's end is the exact propagation to
// the next boundary and that boundary's tail, a stretch from the start to a stamp the head of the
// last boundary before it and the exact propagation from there.
//
// Each interval's maps are made the second time it is used after a change of the parameters (46 us
// for an interval of 86 slices whose decompositions are made, about three crossings of it one by
// one at 14 us; applying the whole map then costs 7 ns: a scratch timing on the seed servo at
// 1000 rpm), so a stiffness that changes at every interval never makes them, no input pays for the
// whole period at once, and they depend on the inputs only, not on when the work is done (a replay
// gives the same bytes). The storage is sized once for the grid: no allocation after the first
// period.
#pragma once

#include <vector>

#include "drivetrain_stiffness/core/sliced_modal_propagator.hpp"

namespace drivetrain_stiffness {

class SlicedIntervalMaps {
 public:
  using AffineMap = SlicedModalPropagator::AffineMap;
  /// `intervals` per mesh period (>= 1) at mesh frequency f > 0 [Hz], over `slices` (the sliced
  /// mesh the propagator runs). InvalidInput otherwise.
  SlicedIntervalMaps(const SlicedMesh& slices, int intervals, double f);

  /// The propagator's parameters changed: every interval is made again when next used.
  void invalidate();
  int intervals() const { return static_cast<int>(intervals_.size()); }
  double meshFrequency() const { return f_; }

  /// Interval i's boundaries: 0 is its start, boundaries(i) its end, the slice boundaries inside
  /// it between them.
  int boundaries(int i) const {
    return static_cast<int>(intervals_[static_cast<std::size_t>(i)].offset.size()) - 1;
  }
  /// Boundary m of interval i as a phase offset from the interval's start [turns].
  double offset(int i, int m) const {
    return intervals_[static_cast<std::size_t>(i)].offset[static_cast<std::size_t>(m)];
  }
  /// The last boundary at or before the phase offset u [turns] from interval i's start (0 for u <=
  /// 0).
  int boundaryAtOrBefore(int i, double u) const;

  /// y from boundary m of interval i to the interval's end (m = 0: the whole interval), with the
  /// drive force F_d [N] held. false (y untouched) where a slice had no usable eigenbasis, or the
  /// interval is met for the first time since the last invalidate() (its maps are made on the
  /// kUsesBeforeMaking-th call for it: the caller crosses the slices one by one until then).
  bool toEnd(const SlicedModalPropagator& exact, int i, int m, State6& y, double drive_force);
  /// Interval i's maps ready for use: made now if this is its kUsesBeforeMaking-th call (toEnd and
  /// fromStart call it; a caller that has work to do before applying a map asks first).
  bool available(const SlicedModalPropagator& exact, int i);
  /// y from interval i's start to its boundary m.
  bool fromStart(const SlicedModalPropagator& exact, int i, int m, State6& y, double drive_force);
  /// Intervals made since construction (each made again after every invalidate() when used).
  long intervalsMade() const { return made_; }
  /// The call for an interval (toEnd or fromStart) since the last invalidate() that makes its maps.
  static constexpr int kUsesBeforeMaking = 2;

 private:
  struct Interval {
    std::vector<double> offset;   ///< boundary phases from the interval's start [turns]
    std::vector<int> slice;       ///< the slice of the piece from boundary m to m + 1
    std::vector<AffineMap> head;  ///< start -> boundary m
    std::vector<AffineMap> tail;  ///< boundary m -> end
    int uses = 0;                 ///< calls since the last invalidate(), until made
    bool ready = false, usable = false;
  };

  /// Makes interval i's maps from the slices' exact maps (each slice decomposed as it is needed).
  bool make(const SlicedModalPropagator& exact, int i);
  std::vector<Interval> intervals_;
  double f_;
  long made_ = 0;
  AffineMap piece_;  ///< scratch: one slice's map
};

}  // namespace drivetrain_stiffness

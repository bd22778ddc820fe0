// The crossing of the slices: the sliced model's exact solution carried step by step, to each
// slice boundary, each change of the contacts or the end (docs/model.md "Following the rig's
// motion"). A part of SlicedModalPropagator.
#pragma once

#include "drivetrain_stiffness/core/dynamics/sliced_event_location.hpp"

namespace drivetrain_stiffness {
namespace sliced {

/// Carries a state through the slices in the linear regimes, counting what it did.
class SliceCrossing {
 public:
  /// Changes of the contacts per call beyond which they are chatter: handed back.
  static constexpr int kMaxChangesPerCall = 64;
  /// Propagates y over duration [s] from phase [turns] at signed mesh frequency f [Hz], drive
  /// force [N] held, through every change between linear regimes. Returns the time propagated [s]:
  /// less than duration where no linear regime holds.
  double propagateLinear(const ContactRules& rules, const SliceTables& tables, State6& y,
                         double& phase, double f, double duration, double drive_force) const;
  /// Changes of the contacts located and gone through.
  long regimeChanges() const { return events_; }
  /// Steps cut short where the regime bound could not clear them.
  long checkedSubsteps() const { return substeps_; }
  /// Slice boundaries crossed.
  long slicesCrossed() const { return crossed_; }

 private:
  /// The walk through the slices: rules and modes, state, phase (whole turns and fraction), time
  /// left [s], TE phasor, slice, regime, changes met.
  struct Walk {
    const ContactRules* rules = nullptr;
    const SliceTables* tables = nullptr;
    State6 z, z_end;
    double whole = 0.0, frac = 0.0, remaining = 0.0;
    Complex e_theta;
    int j = -1;
    MeshRegime regime = MeshRegime::kBothFlanks;
    int changes = 0;
  };
  /// One step of the walk (to a boundary, a change or the end); false where it hands back.
  bool walkStep(Walk& k, double f, double drive_force) const;
  /// The step's length [s] to the slice boundary or the end; its end phase and whether it crosses.
  double stepLength(const Walk& k, double f, double& next, bool& crossing) const;
  /// The step taken: phase, slice crossed, regime on the far side; false in none.
  bool endStep(Walk& k, double f, double h, double next, bool crossing, bool leaves,
               Complex e_end) const;
  /// The regime the walk's state is in, in its slice; false in none.
  bool takeRegime(Walk& k, double w) const;

  mutable Piece piece_;
  mutable long crossed_ = 0, substeps_ = 0, events_ = 0;
};

}  // namespace sliced
}  // namespace drivetrain_stiffness

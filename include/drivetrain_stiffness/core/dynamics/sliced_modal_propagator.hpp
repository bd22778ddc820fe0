// Exact propagation of the gear-rotor model's linear regimes at any speed over the sliced model
// (docs/model.md "Following the rig's motion"), composed of sliced_contact_rules.hpp,
// sliced_slice_tables.hpp, sliced_modal_step.hpp, sliced_event_location.hpp and
// sliced_slice_crossing.hpp.
#pragma once

#include <memory>
#include <optional>

#include "drivetrain_stiffness/core/dynamics/sliced_slice_crossing.hpp"

namespace drivetrain_stiffness {

class SlicedModalPropagator {
 public:
  /// te_amplitude [m], backlash [m]. Throws InvalidInput (bearing clearance, bad parameters).
  SlicedModalPropagator(const GearRotorParameters& p, std::shared_ptr<const SlicedMesh> slices,
                        double te_amplitude, double backlash);
  /// New parameters: slices decomposed again on next use, or a kept set's taken back.
  void setParameters(const GearRotorParameters& p);
  /// Parameter sets whose decompositions are kept.
  static constexpr int kKeptParameterSets = sliced::SliceTables::kKeptParameterSets;
  /// The parameters of now.
  const GearRotorParameters& parameters() const { return tables_.parameters(); }

  /// Propagates y over duration [s] from phase [turns] at signed mesh frequency f [Hz], drive
  /// force [N] held, through every change between linear regimes. Returns the time propagated [s]:
  /// less than duration where no linear regime holds; 0, untouched, for non-finite arguments.
  double propagateLinear(State6& y, double& phase, double f, double duration,
                         double drive_force) const;
  /// The same, all or nothing: false, y and phase untouched, where propagateLinear stops short.
  bool propagate(State6& y, double& phase, double f, double duration, double drive_force) const;
  /// Lower bound of the fastest mode's period [s], 2 pi / sqrt(trace(M^-1 K)) at the stiffest
  /// slice.
  double fastestPeriodBound() const { return fastest_period_bound_; }
  /// Changes of the contacts located and gone through.
  long regimeChanges() const { return crossing_.regimeChanges(); }
  /// Monodromy over one mesh period at mesh frequency f != 0 [Hz], every contact loaded.
  Matrix6 monodromy(double f) const;
  /// The same in the regime y is in at phase [turns]; nullopt in none.
  std::optional<Matrix6> monodromy(double f, const State6& y, double phase) const;
  /// Slices decomposed.
  long decompositions() const { return tables_.decompositions(); }
  /// Of those, by Eigen's general eigensolver.
  long generalDecompositions() const { return tables_.generalDecompositions(); }
  /// Steps cut short where the regime bound could not clear them.
  long checkedSubsteps() const { return crossing_.checkedSubsteps(); }
  /// Slice boundaries crossed.
  long slicesCrossed() const { return crossing_.slicesCrossed(); }
  /// y -> phi y + drive F_d + forced over a stretch at a constant speed.
  struct AffineMap {
    Matrix6 phi = Matrix6::Identity();
    State6 drive = State6::Zero(), forced = State6::Zero();
    void apply(State6& y, double drive_force) const { y = phi * y + drive * drive_force + forced; }
    /// y -> this(first(y)), into out.
    void after(const AffineMap& first, AffineMap& out) const {
      out.phi.noalias() = phi * first.phi;
      out.drive.noalias() = phi * first.drive;
      out.drive += drive;
      out.forced.noalias() = phi * first.forced;
      out.forced += forced;
    }
  };
  /// The loaded regime's exact map over h [s] in slice j from phase [turns] at f [Hz]; false where
  /// the slice has no usable eigenbasis.
  bool loadedSliceMap(int j, double phase, double f, double h, AffineMap& out) const;
  /// The loaded regime's swing gain at settleGain's 16 phases (+inf without an eigenbasis).
  double loadedSwingGain() const;
  /// y at phase [turns] is in the loaded regime.
  bool inLoadedRegime(const State6& y, double phase, double f) const;
  /// The sliced mesh.
  const SlicedMesh& slices() const { return rules_.slices(); }
  /// setParameters calls that took a kept set back.
  long keptSetsReused() const { return tables_.keptSetsReused(); }

 private:
  /// Regime r's monodromy over one mesh period at f [Hz].
  Matrix6 monodromyIn(sliced::MeshRegime r, double f) const;

  sliced::ContactRules rules_;
  sliced::SliceTables tables_;
  sliced::SliceCrossing crossing_;
  mutable sliced::Piece piece_;  ///< loadedSliceMap's set-up
  double fastest_period_bound_ = 0.0;
};

/// The first dopri5 stretch through a moment in no linear regime, in fastest periods
/// (docs/model.md "Following the rig's motion").
inline constexpr double kFirstNonlinearStretch = 1.0 / 16.0;
/// Stretches per call before the rest goes to `nonlinear` in one piece.
inline constexpr long kMaxNonlinearStretches = static_cast<long>(256 / kFirstNonlinearStretch);
/// y and phase [turns] from t to t_end [s] at f [Hz], drive force [N] held: exact in the linear
/// regimes, `nonlinear(t0, t1, y, phase)` (dopri5) through the rest in doubling stretches. Returns
/// the stretches.
template <typename Nonlinear>
long propagateMeasured(const SlicedModalPropagator& exact, State6& y, double& phase, double f,
                       double t, double t_end, double drive_force, Nonlinear&& nonlinear) {
  long stretches = 0;
  const double first = kFirstNonlinearStretch * exact.fastestPeriodBound();
  double stretch = first;
  while (t < t_end) {
    const double left = t_end - t;
    const double done = exact.propagateLinear(y, phase, f, left, drive_force);
    if (done >= left) break;
    t += done;
    if (!(t < t_end)) break;
    stretch = done > 0.0 ? first : stretch;
    const double end =
        ++stretches > kMaxNonlinearStretches || stretch >= t_end - t ? t_end : t + stretch;
    nonlinear(t, end, y, phase);
    t = end;
    stretch *= 2.0;  // the next one, should the exact propagation still not start there
  }
  return stretches;
}

}  // namespace drivetrain_stiffness

// Exact propagation of the gear-rotor model's linear regimes at any speed: the sliced model
// (sliced_mesh.hpp), one eigen-decomposition per slice and regime, each modal coordinate in closed
// form by variation of constants (docs/model.md "Following the rig's motion").
#pragma once

#include <array>
#include <complex>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/core/gear_rotor_model.hpp"
#include "drivetrain_stiffness/core/sliced_mesh.hpp"

namespace drivetrain_stiffness {

class SlicedModalPropagator {
 public:
  /// te_amplitude [m], backlash [m]. Throws InvalidInput (bearing clearance, bad parameters).
  SlicedModalPropagator(const GearRotorParameters& p, std::shared_ptr<const SlicedMesh> slices,
                        double te_amplitude, double backlash);
  /// New parameters: slices decomposed again on next use, or a kept set's taken back.
  void setParameters(const GearRotorParameters& p);
  /// Parameter sets whose decompositions are kept.
  static constexpr int kKeptParameterSets = 6;
  const GearRotorParameters& parameters() const { return p_; }

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
  long regimeChanges() const { return events_; }
  /// Monodromy over one mesh period at mesh frequency f != 0 [Hz], every contact loaded.
  Matrix6 monodromy(double f) const;
  /// The same in the regime y is in at phase [turns]; nullopt in none.
  std::optional<Matrix6> monodromy(double f, const State6& y, double phase) const;
  long decompositions() const { return decompositions_; }
  /// Of those, by Eigen's general eigensolver.
  long generalDecompositions() const { return general_decompositions_; }
  /// Steps cut short where the regime bound could not clear them.
  long checkedSubsteps() const { return substeps_; }
  long slicesCrossed() const { return crossed_; }
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
  const SlicedMesh& slices() const { return *slices_; }
  /// setParameters calls that took a kept set back.
  long keptSetsReused() const { return kept_sets_reused_; }

 private:
  using Complex = std::complex<double>;
  using CVector = Eigen::Matrix<Complex, 6, 1>;
  using CMatrix = Eigen::Matrix<Complex, 6, 6>;
  /// One flank's contact (the Modelica ElastoBacklash rule): each state is linear.
  enum class FlankState { kUnloaded = 0, kLoaded = 1, kStiffened = 2 };
  /// The drive flank's and the back path's states, index 3 drive + back.
  enum class MeshRegime {
    kNoContact = 0,
    kBackFlank = 1,
    kBackStiffened = 2,
    kDriveFlank = 3,
    kBothFlanks = 4,
    kDriveLoadedBackStiffened = 5,
    kDriveStiffened = 6,
    kDriveStiffenedBackLoaded = 7,
    kBothStiffened = 8
  };
  static constexpr int kRegimes = 9;
  static MeshRegime regimeOf(FlankState drive, FlankState back) {
    return static_cast<MeshRegime>(3 * static_cast<int>(drive) + static_cast<int>(back));
  }
  static FlankState driveState(MeshRegime r) {
    return static_cast<FlankState>(static_cast<int>(r) / 3);
  }
  static FlankState backState(MeshRegime r) {
    return static_cast<FlankState>(static_cast<int>(r) % 3);
  }
  /// Mesh force = stiffness delta + damping delta' + constant.
  struct MeshTerms {
    double stiffness, damping, constant;
  };
  MeshTerms meshTerms(MeshRegime r, int j) const;
  /// Every contact of the mesh loaded.
  MeshRegime loadedRegime() const {
    return slices_->antiBacklash() ? MeshRegime::kBothFlanks : MeshRegime::kDriveFlank;
  }
  struct Slice {
    CMatrix v, v_inv;
    CVector lambda, force_dir, drive_dir;  ///< eigenvalues, V^-1 e_F, V^-1 e_v
    std::array<Complex, 6> deflection{};   ///< weight_k (1, -1, 1) . u_k per mode
    std::array<double, 6> weight{};        ///< y = sum_k weight_k Re(V_k eta_k)
    std::array<Complex, 3> upper{};        ///< eigenvalues with Im > 0: the next seeds
    double fastest = 0.0;                  ///< max |lambda| [1/s]
    bool ready = false, usable = false, has_upper = false;
  };
  /// Spring force c0 + alpha delta, plus damper beta delta'; `exists` false without stiffness.
  struct FlankLaw {
    double c0, alpha, beta;
    bool exists;
  };
  FlankLaw flankLaw(int flank, int j) const;
  double driveFlankDamping(int j) const;
  /// c0 + alpha delta + beta delta' > 0 (strict) or >= 0, with regimeMargin's scales.
  struct ContactCondition {
    double c0, alpha, beta, abs_alpha, abs_beta, inverse_scale;
    bool strict;
  };
  /// `first` holds, or (either) `first` or `second`.
  struct Clause {
    ContactCondition first{}, second{};
    bool either = false;
  };
  /// Regime r's rules in slice j; `possible` false where it has no stiffness there.
  struct RegimeConditions {
    std::array<Clause, 6> c{};
    int n = 0;
    bool possible = true;
    MeshTerms terms{0.0, 0.0, 0.0};
  };
  RegimeConditions makeConditions(MeshRegime r, int j) const;
  /// Regime r's rules in slice j, tabulated when r is first met.
  const RegimeConditions& conditions(MeshRegime r, int j) const {
    std::vector<RegimeConditions>& table = conditions_[static_cast<std::size_t>(r)];
    if (table.empty()) tabulateRegimeConditions(r);
    return table[static_cast<std::size_t>(j)];
  }
  void tabulateRegimeConditions(MeshRegime r) const;
  const Slice& slice(MeshRegime r, int j) const;
  /// Slice j's modes by Newton from three seeds; false where not verified.
  bool decomposeSeeded(MeshRegime r, int j, Slice& s, std::array<Complex, 3> seeds) const;
  /// Slice j's modes by Eigen's EigenSolver.
  void decomposeGeneral(MeshRegime r, int j, Slice& s) const;
  Matrix6 systemMatrix(MeshRegime r, int j) const;
  /// propagateLinear's walk through the slices: state, phase (whole turns and fraction), time left
  /// [s], TE phasor, slice, regime, changes met.
  struct Walk {
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
  /// One step's modal set-up from y in slice j, independent of its length.
  struct Piece {
    int n = 0;
    std::array<int, 6> k{};
    std::array<Complex, 6> eta0{}, force_p{}, force_q{}, force_g{}, pf{}, qf{}, gf{}, r0{};
    std::array<double, 6> n1{}, n2{}, nl{};  ///< |iw - lambda|^2, |-iw - lambda|^2, |lambda|^2
    std::array<bool, 6> particular{};
  };
  void prepare(const Slice& s, MeshRegime r, int j, const State6& y, Complex e_theta0, double w,
               double drive_force, Piece& out) const;
  /// y over h [s] from the prepared piece, given e^{i w h}.
  void advance(const Slice& s, const Piece& piece, double w, double h, Complex e_mu,
               State6& y) const;
  /// The first length in a step of h [s] at which the exact solution leaves r (its phasor in
  /// *e_hi).
  double locateChange(const Slice& s, const Piece& piece, MeshRegime r, int j, Complex e_theta,
                      double w, double h, const State6& start, const State6& end,
                      Complex* e_hi) const;
  /// >= 0 in regime r: the least rule's force over its scale.
  double regimeValue(MeshRegime r, int j, const State6& y, Complex e_theta, double w) const;
  /// The contacts at y are those of regime r, given e^{i theta}.
  bool inRegime(MeshRegime r, int j, const State6& y, Complex e_theta, double w) const;
  /// Lower bound of regime r's rules over the step: > 0 proves r holds through it.
  double regimeMargin(const Slice& s, MeshRegime r, int j, const Piece& piece, Complex e_theta0,
                      double w) const;
  /// The linear regime y is in, if any.
  std::optional<MeshRegime> regimeAt(int j, const State6& y, Complex e_theta, double w) const;
  Matrix6 monodromyIn(MeshRegime r, double f) const;

  GearRotorParameters p_;
  std::shared_ptr<const SlicedMesh> slices_;
  double te_amplitude_, backlash_, m_s_ = 0.0;
  /// What a decomposition reads of the parameters: a kept set is taken back where all are equal.
  struct DecompositionKey {
    std::array<double, 2> bearing_stiffness{}, bearing_damping{};
    double mesh_damping = 0.0, pinion_mass = 0.0, gear_mass = 0.0, mesh_mass = 0.0;
    bool operator==(const DecompositionKey& o) const {
      return bearing_stiffness == o.bearing_stiffness && bearing_damping == o.bearing_damping &&
             mesh_damping == o.mesh_damping && pinion_mass == o.pinion_mass &&
             gear_mass == o.gear_mass && mesh_mass == o.mesh_mass;
    }
  };
  /// One parameter set's slices, per MeshRegime, per slice.
  struct KeptSet {
    DecompositionKey key;
    long last_used = 0;
    std::array<std::vector<Slice>, kRegimes> slices;
  };
  std::vector<Slice>& activeSlices(MeshRegime r) const {
    return sets_[active_].slices[static_cast<std::size_t>(r)];
  }
  mutable std::array<KeptSet, kKeptParameterSets> sets_;
  std::size_t active_ = 0;
  int previous_ = -1;  ///< the set before the last change, -1: none
  long use_clock_ = 0, kept_sets_reused_ = 0;
  mutable std::array<std::vector<RegimeConditions>, kRegimes> conditions_;
  /// The mesh damping conditions_ was made with (NaN: not yet).
  double conditions_mesh_damping_ = std::numeric_limits<double>::quiet_NaN();
  mutable Piece piece_;
  mutable long decompositions_ = 0, general_decompositions_ = 0, crossed_ = 0, substeps_ = 0,
               events_ = 0;
  double fastest_period_bound_ = 0.0;
  static constexpr int kEventHalvings = 40;
  /// locateChange's equal lengths per step.
  static constexpr int kEventSamples = 8;
  /// regimeValue at or below this is rounding: locateChange halves there.
  static constexpr double kRoundingValue = 1e-10;
  static constexpr int kMaxChangesPerCall = 64;  ///< more is chatter: handed back
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

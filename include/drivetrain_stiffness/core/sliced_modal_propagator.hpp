// Exact propagation of the gear-rotor model's linear regime at any speed: the propagator of the
// sliced model (sliced_mesh.hpp) over any duration, from one eigen-decomposition per slice.
//
// Inside slice j the model is linear time-invariant while its contacts keep their state (each flank
// unloaded, loaded or stiffened: both anti-backlash flanks loaded, the drive flank alone above the
// knee or the back path alone past the reverse knee, a flank's damper clipped as it opens or
// lands; an ordinary gear's drive or back flank; bearings without clearance):
//   y' = A_j y + e_F (-k_s,j A sin(theta) - c_s A w cos(theta) + F_0) + e_v F_d / m_s,
// with k_s, c_s and the constant F_0 of the regime (meshTerms: 0, +F_p, -F_p, -k1 b or +k1 b; a
// stiffened flank twice its stiffness and constant, no damper),
// theta = 2 pi phi(t) = theta_0 + w s (w = 2 pi f, f the signed mesh frequency, constant between
// encoder readings), e_F = (0, 0, 0, -1/m_p, 1/m_g, -1/m_s) (the mesh force's action, docs/model.md
// eqs M1-M3), F_d the drive force (torque held). With A_j = V diag(lambda) V^-1 and eta = V^-1 y,
// each modal coordinate obeys eta' = lambda eta + P e^{i w s} + Q e^{-i w s} + G, whose solution is
// closed form (variation of constants):
//   eta(h) = e^{lambda h} eta(0) + P E(lambda, i w, h) + Q E(lambda, -i w, h) + G E(lambda, 0, h),
//   E(lambda, mu, h) = integral_0^h e^{lambda (h - s)} e^{mu s} ds = (e^{mu h} - e^{lambda h}) /
//   (mu - lambda)
// (phi_1 series near mu = lambda). The step length h is free: a sample, the time to the next slice
// boundary, the time to an input's stamp. Nothing depends on the speed, so a speed that changes at
// every encoder reading, stands still (w = 0) or reverses (w < 0) costs nothing to set up. Work per
// slice crossed: for each conjugate pair of modes one (the other is its conjugate for a real
// state), so three rows of V^-1 y, three complex exponentials and three columns of V back.
//
// The decomposition of a slice is made the first time the slice is crossed after a change to
// parameters whose slices are not kept (setParameters, below), so a bearing-stiffness change
// costs nothing at the input that made it:
// the work spreads over the next mesh period, about 2 us per slice (Newton from the
// neighbouring slice's modes), and the results do not depend on when it is done (deterministic
// replay). Each regime has its own slices' modes, made as the motion first needs them.
//
// The decompositions of the last kKeptParameterSets parameter sets are kept: a set met again (the
// same bearing stiffness, damping and masses, equal as numbers) takes its slices back with no work.
// The online estimator moves the bearing stiffness on a 1 % grid (DynamicsEstimator), so under a
// rippling load, where the stiffness swings by a few per cent at the ripple's frequency and its
// grid values come back hundreds of times a second, the slices are decomposed once per value.
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
  /// Throws InvalidInput for bearing clearance (the model is then never linear) or bad parameters.
  SlicedModalPropagator(const GearRotorParameters& p, std::shared_ptr<const SlicedMesh> slices,
                        double te_amplitude, double backlash);
  /// New parameters (bearing stiffness, damping): every slice is decomposed again on its next use,
  /// unless the set is one of the last kKeptParameterSets met, whose slices come back as they were.
  void setParameters(const GearRotorParameters& p);
  /// Parameter sets whose decompositions are kept (about 1.3 MB each for the three usual regimes
  /// of a 259-slice mesh, more where the stiffened regimes are met).
  static constexpr int kKeptParameterSets = 6;
  const GearRotorParameters& parameters() const { return p_; }

  /// Propagates y over `duration` [s] (>= 0) from the mesh phase `phase` [turns] at the signed mesh
  /// frequency f [Hz] with the drive force F_d [N] held, through every change of the contacts from
  /// one linear regime to another (a flank lifting above the knee, its damper clipping as it opens
  /// or lands, landing again), each located on the exact solution. Returns the time propagated [s],
  /// y and phase moved to it: `duration` when the whole stretch was linear, less where the state
  /// entered no linear regime (both flanks unloaded at once: no mesh stiffness), a slice had no
  /// usable eigenbasis or a call met more than kMaxChangesPerCall changes; the caller integrates on
  /// from there (dopri5) and calls again.
  double propagateLinear(State6& y, double& phase, double f, double duration,
                         double drive_force) const;
  /// Returns 0, y and phase untouched, for a negative or NaN duration or a non-finite f, phase or
  /// drive force.
  /// The same all or nothing: false, leaving y and phase as they were, where propagateLinear would
  /// stop short.
  bool propagate(State6& y, double& phase, double f, double duration, double drive_force) const;
  /// A lower bound of the period of the fastest mode [s] over every slice and regime, 2 pi /
  /// sqrt(trace(M^-1 K)) at the stiffest slice (the trace bounds the largest eigenvalue of the
  /// undamped problem, all of them >= 0): the time scale of propagateMeasured's dopri5 stretches
  /// through a nonlinear moment (the first is kFirstNonlinearStretch of it).
  double fastestPeriodBound() const { return fastest_period_bound_; }
  /// Changes of the contacts located and gone through (inside a step or on a slice boundary).
  long regimeChanges() const { return events_; }
  /// Homogeneous propagator over one mesh period at mesh frequency f != 0 (the monodromy matrix of
  /// the sliced model at a constant speed) with every contact of the mesh loaded: both
  /// anti-backlash flanks, an ordinary gear's drive flank.
  Matrix6 monodromy(double f) const;
  /// The same in the contact regime that y is in at mesh phase `phase` [turns]: both flanks below
  /// the anti-backlash knee, the drive flank alone above it, the back path alone past the reverse
  /// knee (an ordinary gear: its drive or its back flank), for the Floquet margin of the motion the
  /// node follows. nullopt where y is in none of those (a flank just landed, its damper clipped at
  /// twice the spring, or opening, its damper clipped at zero; no mesh contact): no period-long
  /// linearisation describes it.
  std::optional<Matrix6> monodromy(double f, const State6& y, double phase) const;
  long decompositions() const { return decompositions_; }
  /// Of those, the ones Eigen's general eigensolver made (no seed, or the seeded solve refused).
  long generalDecompositions() const { return general_decompositions_; }
  /// Steps cut short because the bound could not show the contacts keep their state through them.
  long checkedSubsteps() const { return substeps_; }
  long slicesCrossed() const { return crossed_; }
  /// An affine map of the state over a stretch at a constant speed, y -> phi y + drive F_d + forced
  /// (forced: the TE forcing and the regime's constant, from rest), for products over fixed phase
  /// spans (SlicedIntervalMaps). Exact where the contacts keep the loaded regime throughout.
  struct AffineMap {
    Matrix6 phi = Matrix6::Identity();
    State6 drive = State6::Zero(), forced = State6::Zero();
    void apply(State6& y, double drive_force) const { y = phi * y + drive * drive_force + forced; }
    /// This map after `first` (y -> this(first(y))), into out.
    void after(const AffineMap& first, AffineMap& out) const {
      out.phi.noalias() = phi * first.phi;
      out.drive.noalias() = phi * first.drive;
      out.drive += drive;
      out.forced.noalias() = phi * first.forced;
      out.forced += forced;
    }
  };
  /// The exact map of the loaded regime (both anti-backlash flanks loaded; an ordinary gear's drive
  /// flank: monodromy()'s) over h >= 0 [s] inside slice j, from mesh phase `phase` [turns, within
  /// the slice] at mesh frequency f [Hz]: the same solution propagateLinear steps along (prepare,
  /// advance), as a matrix. false where the slice has no usable eigenbasis in that regime.
  bool loadedSliceMap(int j, double phase, double f, double h, AffineMap& out) const;
  /// The loaded regime's swing gain at the phases PeriodicExponentialPropagator::settleGain reads
  /// ((i + 1/2) / 16 of a period), from the slices' modes there: max of sum_k |c v_k| |w_k e_x|.
  /// +inf where one of those slices has no usable eigenbasis.
  double loadedSwingGain() const;
  /// y at mesh phase `phase` [turns] is in that loaded regime (the contacts' rules at one instant).
  bool inLoadedRegime(const State6& y, double phase, double f) const;
  const SlicedMesh& slices() const { return *slices_; }
  /// setParameters calls that switched to another kept set (whose slices decomposed before are
  /// taken back as they were; the others are decomposed as they are crossed).
  long keptSetsReused() const { return kept_sets_reused_; }

 private:
  using Complex = std::complex<double>;
  using CVector = Eigen::Matrix<Complex, 6, 1>;
  using CMatrix = Eigen::Matrix<Complex, 6, 6>;
  /// One flank's contact (GearRotorModel::forces' rule for a compressive contact, the Modelica
  /// ElastoBacklash one): unloaded (open, or closed with its damper clipped at zero force while
  /// it opens: no force either way), loaded (spring and damper), or stiffened (closed with its
  /// damper clipped at twice the spring force, as it does for a moment after every landing: a
  /// spring of twice the stiffness and no damper). Each is linear.
  enum class FlankState { kUnloaded = 0, kLoaded = 1, kStiffened = 2 };
  /// The mesh's contacts: the drive flank's state and the back path's (an ordinary gear: its back
  /// flank's), index 3 drive + back. Below the anti-backlash knee both flanks are loaded, above it
  /// the back path is lifted (kDriveFlank), past the reverse knee the drive flank (kBackFlank); an
  /// ordinary gear is on its drive or its back flank. The stiffened states last microseconds after
  /// a flank lands. Each regime is linear with its own slices' modes, made as the motion first
  /// needs them; both flanks unloaded has no mesh stiffness (a free mass, no eigenbasis) and is
  /// not propagated here.
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
  /// The mesh force in a regime: stiffness * delta + damping * delta' + constant.
  struct MeshTerms {
    double stiffness, damping, constant;
  };
  MeshTerms meshTerms(MeshRegime r, int j) const;
  /// Every contact of the mesh loaded: both anti-backlash flanks, an ordinary gear's drive flank.
  MeshRegime loadedRegime() const {
    return slices_->antiBacklash() ? MeshRegime::kBothFlanks : MeshRegime::kDriveFlank;
  }
  struct Slice {
    CMatrix v, v_inv;
    CVector lambda, force_dir, drive_dir;  ///< eigenvalues, V^-1 e_F, V^-1 e_v
    /// Per mode, weight_k g . u_k with g = (1, -1, 1): the mode's share of the mesh deflection,
    /// which regimeMargin reads at every step; made once per decomposition.
    std::array<Complex, 6> deflection{};
    /// y = sum_k weight_k Re(V_k eta_k): 2 for one member of a conjugate pair (the other, whose
    /// modal coordinate is its conjugate for a real state, gets 0), 1 for a real eigenvalue.
    std::array<double, 6> weight{};
    /// The three eigenvalues with positive imaginary part (when the spectrum is three complex
    /// pairs): the seeds of this slice's next decomposition and of its neighbours'.
    std::array<Complex, 3> upper{};
    double fastest = 0.0;  ///< max |lambda| [1/s]
    bool ready = false, usable = false, has_upper = false;
  };
  /// One flank's contact law in slice j: spring force s = c0 + alpha delta, spring and damper
  /// t = s + beta delta'; `exists` false where the flank has no stiffness (no tooth pair, no back
  /// path).
  struct FlankLaw {
    double c0, alpha, beta;
    bool exists;
  };
  /// flank 0: the drive flank, 1: the back path (an ordinary gear: the back flank).
  FlankLaw flankLaw(int flank, int j) const;
  /// The anti-backlash drive flank's share of the mesh damping in slice j, c k1 / (k1 + k_c).
  double driveFlankDamping(int j) const;
  /// One contact rule: the force c0 + alpha delta + beta delta' must be > 0 (strict) or >= 0;
  /// |alpha|, |beta| and 1 / (|c0| + |alpha| A) kept for regimeMargin's bound.
  struct ContactCondition {
    double c0, alpha, beta, abs_alpha, abs_beta, inverse_scale;
    bool strict;
  };
  /// A rule of a regime: `first` holds, or (`either`) `first` or `second` (an unloaded flank is
  /// open or its damper is clipped at zero).
  struct Clause {
    ContactCondition first{}, second{};
    bool either = false;
  };
  /// Regime r's contact rules in slice j (at most six); `possible` false where a contact the
  /// regime loads has no stiffness in the slice, or the regime has no mesh stiffness at all.
  struct RegimeConditions {
    std::array<Clause, 6> c{};
    int n = 0;
    bool possible = true;
    MeshTerms terms{0.0, 0.0, 0.0};  ///< meshTerms(r, j), read at every step
  };
  RegimeConditions makeConditions(MeshRegime r, int j) const;
  /// Regime r's tables are sized the first time the regime is met (the stiffened ones may never
  /// be: a node below the knee keeps the three usual regimes' memory only).
  const RegimeConditions& conditions(MeshRegime r, int j) const {
    std::vector<RegimeConditions>& table = conditions_[static_cast<std::size_t>(r)];
    if (table.empty()) tabulateRegimeConditions(r);
    return table[static_cast<std::size_t>(j)];
  }
  void tabulateRegimeConditions(MeshRegime r) const;
  const Slice& slice(MeshRegime r, int j) const;
  /// Slice j's modes by Newton on its characteristic polynomial from three seeds (the common case,
  /// about 2 us with the eigenvectors and checks); false where that does not give a verified
  /// spectrum.
  bool decomposeSeeded(MeshRegime r, int j, Slice& s, std::array<Complex, 3> seeds) const;
  /// Slice j's modes by Eigen's EigenSolver and a complex LU inverse (about 5 us).
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
  /// One step's modal set-up from y inside slice j, independent of the step's length: modal
  /// coordinates, forcing, and the particular solution with the free part R where they exist.
  struct Piece {
    int n = 0;
    std::array<int, 6> k{};
    std::array<Complex, 6> eta0{}, force_p{}, force_q{}, force_g{}, pf{}, qf{}, gf{}, r0{};
    std::array<double, 6> n1{}, n2{}, nl{};  ///< |iw - lambda|^2, |-iw - lambda|^2, |lambda|^2
    std::array<bool, 6> particular{};
  };
  void prepare(const Slice& s, MeshRegime r, int j, const State6& y, Complex e_theta0, double w,
               double drive_force, Piece& out) const;
  /// y over h from the prepared piece, given e^{i w h}.
  void advance(const Slice& s, const Piece& piece, double w, double h, Complex e_mu,
               State6& y) const;
  /// Where, within a step of length h that starts in regime r (slice j, TE phasor e_theta, state
  /// `start`) and ends out of it (state `end`, TE phasor *e_hi), the state leaves r on the prepared
  /// piece's exact solution: the first length found out of r (h itself where the change is at the
  /// end to the resolution), with the TE phasor there in *e_hi (left as it was when that is h).
  double locateChange(const Slice& s, const Piece& piece, MeshRegime r, int j, Complex e_theta,
                      double w, double h, const State6& start, const State6& end,
                      Complex* e_hi) const;
  /// inRegime's rules as one continuous number, >= 0 in regime r: the least rule's force over its
  /// scale (an either-clause: the larger of its two), for locateChange's false position.
  double regimeValue(MeshRegime r, int j, const State6& y, Complex e_theta, double w) const;
  /// The contacts at y are those of regime r (each flank unloaded, loaded or stiffened as r says),
  /// at the TE forcing's phase theta, given e^{i theta}.
  bool inRegime(MeshRegime r, int j, const State6& y, Complex e_theta, double w) const;
  /// A lower bound of regime r's contact conditions over a whole step of length h from y (scaled
  /// to the conditions' forces): > 0 proves the contacts keep their state through it.
  double regimeMargin(const Slice& s, MeshRegime r, int j, const Piece& piece, Complex e_theta0,
                      double w) const;
  /// The linear regime y is in, if any.
  std::optional<MeshRegime> regimeAt(int j, const State6& y, Complex e_theta, double w) const;
  Matrix6 monodromyIn(MeshRegime r, double f) const;

  GearRotorParameters p_;
  std::shared_ptr<const SlicedMesh> slices_;
  double te_amplitude_, backlash_, m_s_ = 0.0;
  /// What a slice's decomposition reads of the parameters (decomposeSeeded, decomposeGeneral; the
  /// slices, the TE amplitude and the backlash are the propagator's own): a kept set is taken back
  /// only where all of these are equal (as doubles: +0 and -0 alike, which give the same results).
  struct DecompositionKey {
    std::array<double, 2> bearing_stiffness{}, bearing_damping{};
    double mesh_damping = 0.0, pinion_mass = 0.0, gear_mass = 0.0, mesh_mass = 0.0;
    bool operator==(const DecompositionKey& o) const {
      return bearing_stiffness == o.bearing_stiffness && bearing_damping == o.bearing_damping &&
             mesh_damping == o.mesh_damping && pinion_mass == o.pinion_mass &&
             gear_mass == o.gear_mass && mesh_mass == o.mesh_mass;
    }
  };
  /// One parameter set's slices, per MeshRegime, per slice (sized when the regime is first met).
  struct KeptSet {
    DecompositionKey key;
    long last_used = 0;  ///< 0: never used (its key means nothing)
    std::array<std::vector<Slice>, kRegimes> slices;
  };
  std::vector<Slice>& activeSlices(MeshRegime r) const {
    return sets_[active_].slices[static_cast<std::size_t>(r)];
  }
  mutable std::array<KeptSet, kKeptParameterSets> sets_;
  std::size_t active_ = 0;  ///< the set of the parameters now
  int previous_ = -1;       ///< the set before the last change (seeds for the new one), -1: none
  long use_clock_ = 0, kept_sets_reused_ = 0;
  mutable std::array<std::vector<RegimeConditions>, kRegimes>
      conditions_;  ///< per MeshRegime, per slice (makeConditions)
  /// The mesh damping the tables of conditions_ were made with (NaN: not yet made). The rules read
  /// nothing else that setParameters can change, so a bearing change keeps them.
  double conditions_mesh_damping_ = std::numeric_limits<double>::quiet_NaN();
  mutable Piece piece_;
  mutable long decompositions_ = 0, general_decompositions_ = 0, crossed_ = 0, substeps_ = 0,
               events_ = 0;
  double fastest_period_bound_ = 0.0;
  static constexpr int kEventHalvings = 40;
  /// locateChange first samples the step at this many equal lengths for the earliest change.
  static constexpr int kEventSamples = 8;
  /// regimeValue at or below this is the rounding of the contact forces (their scale's 1e-16 times
  /// the modal sums' cancellation), not a distance from the boundary: locateChange halves there.
  static constexpr double kRoundingValue = 1e-10;
  static constexpr int kMaxChangesPerCall = 64;  ///< more in one call is chatter: handed back
};

/// The propagation along a measured motion as the online estimator runs it (and the bench's motion
/// scenes, as it): over [t, t_end] at mesh frequency f with the drive force held, exact as far as
/// the contacts stay in linear regimes (propagateLinear), and through each moment in none by
/// `nonlinear(t0, t1, y, phase)` (dopri5 on the same sliced model and motion, moving y and phase to
/// t1), over kFirstNonlinearStretch of the fastest period (fastestPeriodBound) at first, doubled
/// while the exact propagation still cannot start, back to the first length once it has. After
/// kMaxNonlinearStretches stretches in one call the rest of the interval goes to `nonlinear` in one
/// piece (whose own work bound then holds). A template, not a std::function: the estimator's
/// per-input path allocates nothing. Returns the number of stretches.
/// The first stretch, as a fraction of the fastest period (the stretches serve only moments with
/// both flanks unloaded; a clipped damper is a linear regime): a damper clips for a small part of
/// a period where a flank lifts or lands (docs/model.md, "Following the rig's motion"): on the 48 s
/// load_sweep bag a first stretch of a whole period had dopri5 integrate 62.5 ms of rig time in
/// 4,525 stretches, one of 1/16 of a period 7.6 ms in 8,273 (2.1 million right-hand sides against
/// 0.5 million). The doubling search costs one refused propagateLinear per doubling, about a
/// microsecond, against ~10 us of dopri5 per sixteenth of a period at rtol 1e-8.
inline constexpr double kFirstNonlinearStretch = 1.0 / 16.0;
/// At most this many stretches per call: 256 whole-period stretches' worth of the shorter ones
/// (the work bound of a call is about the same as with 256 whole periods: ~10 us of dopri5 and a
/// refused propagateLinear each). Where a flank lifts and lands again after a tiny exact advance,
/// each stretch starts again at the first length, so a 1 ms call could take ~940 stretches at
/// worst (a review's estimate for the seed rig's 17 us period), which the old 256 would have cut
/// off to one dopri5 piece; measured at 0.8-1.2 x the knee torque, the most in one 1 ms call was 80
/// (run_up; 38 with whole-period stretches) and 11 (the chatter test of the time; none now,
/// ChatterAroundTheKneeIsPropagatedExactly).
inline constexpr long kMaxNonlinearStretches = static_cast<long>(256 / kFirstNonlinearStretch);
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

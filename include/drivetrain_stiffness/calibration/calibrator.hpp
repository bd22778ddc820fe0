// Live calibration of the stiffness model against the rig's encoders (docs/calibration.md), free of
// ROS and of any clock: readings arrive with their times as arguments.
//
// Per encoder reading (both shafts' angles, the mesh phase, the held torque):
//  1. the measured TE x = r_b,p theta_p + r_b,g theta_g (static_te_model.hpp), taken modulo the
//     lattice 2 pi r_b,p gcd(z_p, z_g) / z_p that the encoders' unknown whole turns leave;
//  2. into the current window's angle-domain regression (order_regression.hpp). A window spans one
//     gear turn (a whole period of every shaft order) at a steady torque (within ~torque_band and
//     1 %); a torque step, a break in the readings or a reset starts a new one.
// Per closed window:
//  3. |T| <= ~baseline_torque: the window joins the unloaded baseline (mean and mesh harmonics,
//     averaged over baseline windows), which every later window subtracts (it holds the encoders'
//     zeros and the load-free manufacturing TE);
//  4. otherwise, when excited (speed at least ~min_speed_rpm, mesh frequency at most
//     ~max_mesh_to_natural of the lowest natural frequency, readings dense enough for the second
//     mesh harmonic) and a baseline exists: the features (mean TE, |C_1|, |C_2| above the baseline)
//     update an iterated extended Kalman filter over the five parameters (static_te_model.hpp),
//     after a gate on the normalised innovation squared (NIS > ~gate: rejected and counted).
//  5. the confidence bands of the outputs follow from the posterior covariance by linearisation.
// Allocation-free per reading; per window only fixed-size Eigen and the supports' preallocated
// solutions.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "drivetrain_stiffness/calibration/model_error_scale.hpp"
#include "drivetrain_stiffness/calibration/order_regression.hpp"
#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

class StiffnessEstimator;

/// Why the last window did or did not update the estimate.
enum class WindowOutcome {
  kNone,
  kBaseline,
  kUpdated,
  kGated,
  kNoBaseline,
  kTooSlow,
  kNotQuasiStatic,
  kTooSparse,
  kIllConditioned
};
constexpr int kWindowOutcomes = static_cast<int>(WindowOutcome::kIllConditioned) + 1;
const char* toString(WindowOutcome outcome);

/// The calibration's state after a window (every field SI; see the Calibration message).
struct CalibrationEstimate {
  CalibrationVector value = CalibrationVector::Zero();
  CalibrationVector std = CalibrationVector::Zero();
  CalibrationVector prior_std = CalibrationVector::Zero();
  std::array<bool, kCalibrationSize> identified{};  ///< posterior std below half the prior's
  WindowOutcome outcome = WindowOutcome::kNone;
  bool excited = false;   ///< the last window's excitation sufficed (Calibrator::excitation, a
                          ///< conditioned fit); `outcome` says whether it updated
  bool baseline = false;  ///< a baseline exists
  double nis = 0.0;       ///< normalised innovation squared of the last loaded window (3 dof)
  /// Per feature (mean TE, |C_1|, |C_2|): the model-error variance the windows show, as a multiple
  /// of the configured allowance (model_error_scale.hpp); the reported std and bands use it.
  FeatureVector model_error_scale = FeatureVector::Ones();
  std::uint64_t windows = 0, baseline_windows = 0, updates = 0, gated = 0, not_excited = 0;
  double window_torque = 0.0;  ///< [N·m] mean torque of the last window
  double window_speed = 0.0;   ///< [rad/s] mean pinion speed of the last window
  FeatureVector measured = FeatureVector::Zero(), predicted = FeatureVector::Zero(),
                feature_std = FeatureVector::Zero();
  double series_compliance = 0.0,
         series_compliance_std = 0.0;  ///< [m/N] mean TE / F at ~reference_torque
  double mesh_stiffness = 0.0, mesh_stiffness_low = 0.0,
         mesh_stiffness_high = 0.0;  ///< [N/m] at the window torque, 95 %
  std::array<double, 2> bearing_stiffness{}, bearing_stiffness_low{},
      bearing_stiffness_high{};  ///< [N/m] per shaft
  std::array<double, 3> natural_frequency{}, natural_frequency_low{},
      natural_frequency_high{};  ///< [Hz]
  double knee_torque = 0.0;  ///< [N·m] pinion torque where the back half lifts, at the estimate
};

/// A stretch of readings at a steady torque (the window rule's) that did not become a window: it
/// was dropped when the filtered torque left its band or the readings broke off, or it is still
/// open.
struct SteadyStretch {
  long readings = 0;
  double duration = 0.0;  ///< [s] from its first reading to its last
  double angle =
      0.0;  ///< [rad] of pinion angle spanned (a window needs CalibrationProgress::window_angle)
  double torque = 0.0;  ///< [N·m] mean held torque
  double speed = 0.0;   ///< [rad/s] mean pinion speed
};

/// What the calibration has seen, for saying why no window has updated it
/// (Calibrator::waitingReason). Fixed size: kept on the per-reading path without allocation.
struct CalibrationProgress {
  std::uint64_t readings = 0;  ///< encoder readings with the gear angle given to the calibration
  double window_angle = 0.0;   ///< [rad] of pinion angle a window spans: one gear turn
  /// The longest stretch (by angle, then by time) that did not become a window, at a mean
  /// |torque| <= ~baseline_torque (unloaded) and above it (loaded). readings == 0: none seen.
  SteadyStretch unloaded, loaded;
  /// [N·m] the smallest mean |torque| of any stretch or closed window (infinite before the first).
  double smallest_torque = std::numeric_limits<double>::infinity();
  std::uint64_t loaded_windows = 0;  ///< closed windows at a mean |torque| above ~baseline_torque
  std::array<std::uint64_t, kWindowOutcomes> closed{};  ///< closed windows per WindowOutcome
  /// Per WindowOutcome, the number that decided its last window and the limit it was held against:
  /// kTooSlow: speed and ~min_speed_rpm [rpm]; kNotQuasiStatic: mesh frequency and
  /// ~max_mesh_to_natural x the lowest natural frequency [Hz]; kTooSparse: reading rate and the
  /// rate the second mesh harmonic needs [Hz]; kIllConditioned: readings in the fit and the fewest
  /// it takes; kGated, kUpdated: NIS and ~gate; kBaseline, kNoBaseline: mean |torque| and
  /// ~baseline_torque [N·m].
  std::array<double, kWindowOutcomes> value{}, limit{};
  std::uint64_t count(WindowOutcome o) const { return closed[static_cast<std::size_t>(o)]; }
  /// [s] one window (window_angle) at pinion speed `speed` [rad/s]; infinite at rest.
  double windowSeconds(double speed) const;
};

/// The calibrated stiffness and natural frequencies at an operating point with their 95 % bounds
/// (first-order propagation of the parameters' covariance), for the stiffness and resonance
/// outputs.
struct CalibrationBands {
  bool calibrated =
      false;  ///< at least one window updated the parameters (else: the prior's bounds)
  double mesh_stiffness = 0.0, mesh_stiffness_low = 0.0,
         mesh_stiffness_high = 0.0;  ///< [N/m] period mean
  std::array<double, 2> bearing_stiffness{}, bearing_stiffness_low{},
      bearing_stiffness_high{};  ///< [N/m] per shaft
  std::array<double, 3> natural_frequency{}, natural_frequency_low{},
      natural_frequency_high{};  ///< [Hz] (with_modes)
};

/// One processed reading: measured TE with the baseline and the shaft orders removed, and the
/// calibrated model's prediction at the same phase and torque [m].
struct MeasuredTeSample {
  double te = 0.0, predicted = 0.0, residual = 0.0;
  double torque = 0.0;  ///< [N·m] held
  double phase = 0.0;   ///< mesh phase [-]
};

class Calibrator {
 public:
  /// The rig's calibration block gives the priors and the data rules. Throws InvalidInput for a
  /// rig without one, or an invalid one. The rig is read only and shared (the pipeline's); `mesh`,
  /// if given, is the rig's own mesh table (AntiBacklashMesh(rig), read only, shared with the
  /// stiffness estimator), which the static TE model uses instead of building its own when it
  /// holds the drawing's stiffness (StaticTeModel).
  explicit Calibrator(std::shared_ptr<const RigConfig> rig,
                      std::shared_ptr<const AntiBacklashMesh> mesh = nullptr);
  /// The same on a copy of `rig`.
  explicit Calibrator(const RigConfig& rig);

  /// What a reading produced (bit flags).
  enum : int { kNothing = 0, kSample = 1, kWindow = 2 };
  /// One encoder reading at time t [s]: unwrapped pinion and gear angles [rad] (joint_states
  /// convention), mesh phase [-], pinion speed [rad/s], held torque [N·m]; `supports` gives the
  /// bearing models at their current settings. `sample` is filled when kSample is returned.
  int reading(double t, double pinion, double gear, double phase, double speed, double torque,
              const StiffnessEstimator& supports, MeasuredTeSample& sample);
  /// The readings broke off (encoder time-out, a reset, a jump): the open window is dropped.
  void interrupt();
  const CalibrationEstimate& estimate() const { return estimate_; }
  /// What the calibration has seen so far, the open window counted as a stretch. Allocation-free.
  CalibrationProgress progress() const;
  /// Why no window has updated the estimate, as one sentence with the numbers, e.g. "no window
  /// closed: the longest steady torque (1.5 N*m) lasted 1.93 s, 0.96 of a gear turn, and a window
  /// needs one gear turn, 2.00 s at 60 rpm" (docs/calibration.md, "When no window updates");
  /// empty once a window has updated it. Allocates (the string): for /diagnostics and run
  /// summaries, not the per-reading path.
  std::string waitingReason() const;
  const RigConfig& rig() const { return *rig_; }
  const StaticTeModel& model() const { return model_; }
  /// The parameter values (same as estimate().value) and their covariance.
  const CalibrationVector& parameters() const { return estimate_.value; }
  const CalibrationMatrix& covariance() const { return covariance_; }
  /// The filter's own covariance of the parameters, under the configured model-error allowance
  /// (what covariance() reports unless the windows show more model error: model_error_scale.hpp).
  CalibrationMatrix filterCovariance() const;
  /// The calibrated stiffness at pinion torque `torque` (the supports at their current load), and
  /// with `with_modes` the natural frequencies, each with its 95 % bounds. Const; allocation-free.
  CalibrationBands bands(double torque, const StiffnessEstimator& supports, bool with_modes) const;

 private:
  void closeWindow(const StiffnessEstimator& supports);
  /// The excitation rule; `value` and `limit` get the number that decided it and its limit
  /// (CalibrationProgress::value).
  WindowOutcome excitation(double speed, double duration, double& value, double& limit) const;
  /// A closed window's outcome into progress_.
  void noteOutcome(WindowOutcome outcome, double value, double limit);
  /// The open window, about to be dropped without closing, into progress_ as a stretch.
  void noteStretch();
  SteadyStretch openStretch() const;
  void update(const FeatureVector& z, const FeatureVector& z_std, double torque);
  /// The window's torque rule: within ~torque_band plus 1 % of the torque it started at.
  bool inBand(double torque) const;
  void outputs(double torque, const StiffnessEstimator& supports);
  /// sqrt(g' P g) of a scalar function of the parameters, g by central differences at the estimate
  /// (a template, not std::function: a capturing lambda would allocate on the per-window path),
  /// over the parameters whose bits (1 << index) are set in depends_on (the others' g_i are exactly
  /// 0).
  template <typename F>
  double spreadOf(F&& f, std::uint32_t depends_on = ~0u) const;
  FeatureVector predict(const CalibrationVector& p, double torque) const;

  std::shared_ptr<const RigConfig> rig_;
  const CalibrationConfig& config_;  ///< rig_->calibration
  StaticTeModel model_;
  OrderRegression regression_;
  int teeth_[2] = {0, 0};
  double lattice_ = 0.0;  ///< [m] the TE's ambiguity from the encoders' whole turns
  double gear_turn_ =
      0.0;  ///< [rad] of pinion angle a window spans: one gear turn (at least one pinion turn)

  // The filter's state: the parameters with each bearing scale s as its compliance factor c = 1/s.
  // The mean TE is linear in c (u/s = u c), so the direction the encoders cannot see (the pinion's
  // bearing against the gear's, whose deflections enter as a sum) stays exactly unobserved: the
  // updates move both factors alike and leave that direction at its prior. With s itself the
  // linearisation at s_p != s_g leaks into it and the two scales drift apart (measured: 0.65 and
  // 0.93 for a truth of 0.74 and 0.85).
  CalibrationVector state_ = CalibrationVector::Zero(),
                    state_prior_std_ = CalibrationVector::Zero();
  /// The drawing's spread (CalibrationPrior::reference) in the state's coordinates: what
  /// `identified` and the drift are judged against.
  CalibrationVector state_reference_std_ = CalibrationVector::Zero();
  CalibrationMatrix state_covariance_ = CalibrationMatrix::Zero();
  CalibrationMatrix covariance_ =
      CalibrationMatrix::Zero();  ///< of the parameters (scales), by linearisation
  /// The estimate's covariance under the model error the windows show (state coordinates); the
  /// filter's own state_covariance_ keeps the configured allowance and drives the gains.
  ModelErrorScale model_error_;
  /// State to parameters (c -> 1/c for the bearing entries), and that map's Jacobian at the state.
  static CalibrationVector toParameters(const CalibrationVector& state);
  static CalibrationMatrix parameterJacobian(const CalibrationVector& state);
  CalibrationEstimate estimate_;
  CalibrationProgress progress_;
  /// Accepted windows per operating point (torque bins 2 ~torque_band wide), so the model error,
  /// which repeats at one operating point, counts once however long the rig dwells there: window n
  /// of a bin carries n times the per-window model-error variance. Fixed storage (no allocation);
  /// past kBins distinct points the last bin is shared.
  static constexpr int kBins = 256;
  std::array<long, kBins> bin_key_{};
  std::array<std::uint32_t, kBins> bin_count_{};
  int bins_used_ = 0;
  std::uint32_t countAtOperatingPoint(double torque);
  double last_update_t_ = 0.0;
  bool has_update_t_ = false;

  // The open window.
  struct Window {
    bool open = false;
    double t0 = 0.0, t1 = 0.0, torque0 = 0.0, angle_min = 0.0, angle_max = 0.0;
    std::array<double, 2> shafts{};  ///< shaft deflections at torque0 (the per-reading prediction)
    double torque_sum = 0.0, speed_sum = 0.0;
    long n = 0;
  } window_;
  std::optional<double> te_reference_;  ///< the first TE, around which later ones are reduced
  /// The torque the window rule watches: the held torque low-passed with kTorqueFilter, so
  /// measurement noise (0.5 % on a torque sensor is ~0.7 % between two samples) does not end
  /// every window, while a step still ends it within a few time constants.
  static constexpr double kTorqueFilter = 0.02;  ///< [s]
  std::optional<double> filtered_torque_;
  double last_t_ = 0.0;
  StaticTeModel::PhaseHistogram histogram_{};  ///< the open window's sampled mesh phases
  StaticTeModel::SampledPhases sampled_;       ///< the closed window's, prepared for the model
  /// Readings within this fraction of a mesh period of a switching phase stay out of the fit (and
  /// of the model's sampled features): there the TE steps, and a measured phase off by the
  /// encoder's mounting error puts a reading on the wrong side of the step. Ignoring them removed
  /// a 1.5-3 % bias of the mesh harmonics on load_sweep recordings (docs/calibration.md).
  static constexpr double kSwitchGuard = 2e-3;

  // The baseline: running means over the baseline windows.
  double base_torque_ = 0.0, base_mean_ = 0.0, base_mean_var_ = 0.0, base_harm_var_ = 0.0;
  std::array<std::complex<double>, OrderRegression::kMeshHarmonics> base_harmonics_{};
  std::uint64_t base_count_ = 0;
  std::array<double, 2> base_shafts_{};

  // The last fit (its orders are removed from the readings that follow) and the shafts' deflection
  // at the last loaded window (scaled by torque for the per-reading prediction).
  OrderRegression::Fit last_fit_;
  bool has_fit_ = false;
  std::array<double, 2> shafts_{};  ///< at the last loaded window's mean torque
  std::array<double, 2> scratch_{};
};

}  // namespace drivetrain_stiffness

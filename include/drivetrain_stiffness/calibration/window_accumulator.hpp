// The encoder readings' windows: the measured TE on the encoders' lattice, the window rule on the
// held torque, each window's order regression, the unloaded baseline, the features above it and
// the accepted windows per operating point (docs/calibration.md "1. Measured TE" to "3. The
// estimator"). Allocation-free per reading.
#pragma once

#include <array>
#include <complex>
#include <cstdint>
#include <optional>

#include "drivetrain_stiffness/calibration/calibration_report.hpp"
#include "drivetrain_stiffness/calibration/order_regression.hpp"
#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

class StiffnessEstimator;

/// One reading's measured TE without baseline and shaft orders, and the model's prediction [m].
struct MeasuredTeSample {
  double te = 0.0, predicted = 0.0, residual = 0.0;
  double torque = 0.0;  ///< [N·m] held
  double phase = 0.0;   ///< [-] mesh phase
};

class WindowAccumulator {
 public:
  /// The windows of `rig`'s calibration block, on the TE of `model` (not kept).
  WindowAccumulator(const RigConfig& rig, const StaticTeModel& model);

  /// [rad] of pinion angle a window spans: one gear turn.
  double windowAngle() const { return gear_turn_; }
  /// One reading's TE [m] at unwrapped angles [rad], reduced onto the lattice around the first.
  double measuredTe(double pinion, double gear);

  /// What add found (bit flags).
  enum : int { kNothing = 0, kDropped = 1, kSpans = 2 };
  /// Adds a reading at t [s] (angle [rad], mesh phase [-], speed [rad/s], held torque [N·m], TE
  /// [m]). kDropped: the open window left its band, `dropped` its stretch; kSpans: the window
  /// spans a gear turn and awaits close().
  int add(double t, double pinion, double phase, double speed, double torque, double te,
          const StiffnessEstimator& supports, StaticTeModel& model, SteadyStretch& dropped);
  /// Closes the window add reported as spanning a gear turn.
  void close() { window_.open = false; }
  /// Drops the open window and the torque filter's state (the readings broke off).
  void interrupt();
  /// The open window as a stretch (readings 0: none open).
  SteadyStretch openStretch() const;

  /// [N·m] the open window's mean held torque.
  double meanTorque() const;
  /// [rad/s] the open window's mean pinion speed.
  double meanSpeed() const;
  /// [s] the open window's last reading.
  double endTime() const { return window_.t1; }
  /// The excitation rule, then the window's fit, kept for later readings on kUpdated; otherwise
  /// why not, with the number that decided it and its limit. `lowest` [Hz]: the lowest mode.
  WindowOutcome fit(double speed, double lowest, double& value, double& limit);
  /// Adds the fitted window at mean torque [N·m] to the baseline's running means.
  void addBaseline(double torque, const StiffnessEstimator& supports, StaticTeModel& model);
  /// Whether the baseline has a window.
  bool hasBaseline() const { return baseline_.count > 0; }
  /// The fitted window's features above the baseline z and their std at mean torque [N·m];
  /// prepares the shafts' deflection and the sampled phases predictFeatures reads.
  void features(double torque, const StiffnessEstimator& supports, StaticTeModel& model,
                FeatureVector& z, FeatureVector& z_std);
  /// The TE features of the last prepared window at parameters p and torque [N·m].
  FeatureVector predictFeatures(const StaticTeModel& model, const CalibrationVector& p,
                                double torque) const;
  /// [m] shaft s's deflection at the last prepared window's torque less the baseline's.
  double shaftOverBaseline(int s) const { return shafts_[s] - baseline_.shafts[s]; }
  /// Counts a window at torque [N·m]: the count at its operating point, this one included.
  std::uint32_t countAtOperatingPoint(double torque);

  /// The processed reading (TE without baseline and shaft orders, the prediction at parameters
  /// p) once a baseline and a fit exist; returns whether it fills `sample`.
  bool sample(double te, double pinion, double phase, double torque, const CalibrationVector& p,
              const StiffnessEstimator& supports, StaticTeModel& model,
              MeasuredTeSample& sample) const;

 private:
  /// Within ~torque_band plus 1 % of the window's first torque.
  bool inBand(double torque) const;
  /// The excitation rule; sets the number that decided it and its limit.
  WindowOutcome excitation(double speed, double duration, double lowest, double& value,
                           double& limit) const;

  const CalibrationConfig& config_;  ///< rig.calibration
  OrderRegression regression_;
  std::array<double, 2> base_radius_{};  ///< [m] the model's base radii
  int pinion_teeth_ = 0;
  double lattice_ = 0.0;    ///< [m] the TE's ambiguity from the encoders' whole turns
  double gear_turn_ = 0.0;  ///< [rad] of pinion angle a window spans

  /// The open window.
  struct Window {
    bool open = false;
    double t0 = 0.0, t1 = 0.0, torque0 = 0.0, angle_min = 0.0, angle_max = 0.0;
    std::array<double, 2> shafts{};  ///< [m] shaft deflections at torque0
    double torque_sum = 0.0, speed_sum = 0.0;
    long n = 0;
  } window_;
  std::optional<double> te_reference_;  ///< the first TE, around which later ones are reduced
  /// The window rule's low-pass time constant on the held torque (docs/calibration.md "1. Measured
  /// TE").
  static constexpr double kTorqueFilter = 0.02;  ///< [s]
  std::optional<double> filtered_torque_;
  double last_t_ = 0.0;
  StaticTeModel::PhaseHistogram histogram_{};  ///< the open window's sampled mesh phases
  StaticTeModel::SampledPhases sampled_;       ///< the closed window's, prepared for the model
  /// [mesh periods] readings this near a switching phase stay out of the fit (docs/calibration.md
  /// "1. Measured TE").
  static constexpr double kSwitchGuard = 2e-3;

  /// The baseline: running means over the baseline windows.
  struct Baseline {
    double torque = 0.0, mean = 0.0, mean_var = 0.0, harm_var = 0.0;
    std::array<std::complex<double>, OrderRegression::kMeshHarmonics> harmonics{};
    std::uint64_t count = 0;
    std::array<double, 2> shafts{};
  } baseline_;

  /// The last fit, whose orders later readings lose, and the shafts' deflection.
  OrderRegression::Fit last_fit_;
  bool has_fit_ = false;
  std::array<double, 2> shafts_{};  ///< [m] at the last loaded window's mean torque

  /// Accepted windows per torque bin 2 ~torque_band wide (docs/calibration.md "3. The
  /// estimator"); past kBins the last bin is shared.
  static constexpr int kBins = 256;
  std::array<long, kBins> bin_key_{};
  std::array<std::uint32_t, kBins> bin_count_{};
  int bins_used_ = 0;
};

}  // namespace drivetrain_stiffness

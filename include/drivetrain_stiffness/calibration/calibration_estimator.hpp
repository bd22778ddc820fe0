// The calibration's filter: the state, its covariance, the priors and bounds, and the iterated
// update shared by the TE windows and the natural frequencies (docs/calibration.md "3. The
// estimator", "Natural frequencies"). Free of ROS and of the rig's readings; allocation-free.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "drivetrain_stiffness/calibration/calibration_report.hpp"
#include "drivetrain_stiffness/calibration/model_error_scale.hpp"
#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// The values one update measures: a window's TE features, or a record's natural frequencies (one
/// slot per mode of the model; slots past the record's count predicted as 0).
constexpr int kMeasurementSize = 3;
static_assert(kFeatureSize == kMeasurementSize, "the TE features and the modes share the update");
using MeasurementVector = Eigen::Matrix<double, kMeasurementSize, 1>;
using MeasurementMatrix = Eigen::Matrix<double, kMeasurementSize, kMeasurementSize>;
using MeasurementRows = ModelErrorScale::FeatureRows;
using MeasurementGain = ModelErrorScale::Gain;

/// A measurement of the filter's state, as the iterated update relinearises it.
class StateMeasurement {
 public:
  /// The predicted measurement at a state.
  virtual MeasurementVector predict(const CalibrationVector& state) const = 0;
  /// The measurement's Jacobian at a state; held parameters have a zero column.
  virtual void jacobian(const CalibrationVector& state, MeasurementRows& H) const = 0;

 protected:
  ~StateMeasurement() = default;
};

/// How iteratedUpdate iterates: its cap and, for a measurement that bends sharply, the line search.
struct IterationRule {
  int iterations = 4;        ///< Gauss-Newton relinearisations at most
  bool line_search = false;  ///< take a step only where it lowers the posterior's cost
  std::size_t rows = 0;      ///< the measurement rows the cost sums (with the line search)
};

/// What updateFeatures computed for a window, updated or gated.
struct FeatureUpdate {
  double nis = 0.0;                                   ///< normalised innovation squared (3 dof)
  FeatureVector predicted = FeatureVector::Zero();    ///< at the prior state
  FeatureVector feature_std = FeatureVector::Zero();  ///< sqrt of R's diagonal
};

class CalibrationEstimator {
 public:
  /// The prior of the configured calibration block; a parameter whose prior std is 0 is held.
  /// `mean`, `prior_std`, `reference_std` in the parameters' coordinates.
  CalibrationEstimator(const CalibrationConfig& config, const CalibrationVector& mean,
                       const CalibrationVector& prior_std, const CalibrationVector& reference_std);

  /// The state: each bearing scale s as its compliance factor c = 1/s.
  const CalibrationVector& state() const { return state_; }
  /// The prior std in the state's coordinates (0: held).
  const CalibrationVector& priorStd() const { return prior_std_; }
  /// The drawing's spread in the state's coordinates.
  const CalibrationVector& referenceStd() const { return reference_std_; }
  /// The state's covariance under the configured model-error allowance.
  const CalibrationMatrix& stateCovariance() const { return covariance_; }
  /// The model error the windows' innovations show.
  const ModelErrorScale& modelError() const { return model_error_; }
  /// The filter's own covariance in the parameters' coordinates.
  CalibrationMatrix filterCovariance() const;

  /// State to parameters (c -> 1/c).
  static CalibrationVector toParameters(const CalibrationVector& state);
  /// The Jacobian of toParameters at a state.
  static CalibrationMatrix parameterJacobian(const CalibrationVector& state);
  /// Clamps a state to the physical bounds: scales in [0.05, 19.9], T_p >= 0.
  static void bound(CalibrationVector& state);
  /// The random walk since the last update at t [s] (docs/calibration.md "3. The estimator").
  CalibrationMatrix processNoise(double t) const;

  /// The iterated EKF's posterior mode from the state, and the last iteration's H and K; H enters
  /// as the Jacobian at the state, h0 is the prediction there. Returns false when the line search
  /// finds no lower cost at the first step.
  bool iteratedUpdate(const StateMeasurement& measurement, const CalibrationMatrix& prior,
                      const MeasurementMatrix& R, const MeasurementVector& z,
                      const MeasurementVector& h0, const IterationRule& rule, MeasurementRows& H,
                      MeasurementGain& K, CalibrationVector& theta) const;
  /// One window's TE features z (std z_std) at t [s], the window being the `repeats`-th at its
  /// operating point. Returns false when gated (NIS over ~gate).
  bool updateFeatures(const StateMeasurement& features, const FeatureVector& z,
                      const FeatureVector& z_std, double t, double repeats, FeatureUpdate& out);
  /// One record's `count` natural frequencies z (std z_std) of the model's modes `mode` at t [s].
  /// Returns kUpdated, kGated (NIS over the gate or no step lowers the cost; `nis` set) or kNone
  /// (no estimated parameter moves the modes).
  WindowOutcome updateFrequencies(const StateMeasurement& modes, const MeasurementVector& z,
                                  const MeasurementVector& z_std, const std::array<int, 3>& mode,
                                  std::size_t count, double t, double& nis);

 private:
  const CalibrationConfig& config_;
  CalibrationVector state_ = CalibrationVector::Zero(), prior_std_ = CalibrationVector::Zero();
  CalibrationVector reference_std_ = CalibrationVector::Zero();
  CalibrationMatrix covariance_ = CalibrationMatrix::Zero();
  ModelErrorScale model_error_;
  /// Records that carried each mode's frequency (docs/calibration.md "Natural frequencies").
  std::array<std::uint32_t, 3> modal_count_{};
  double last_update_t_ = 0.0;
  bool has_update_t_ = false;
};

}  // namespace drivetrain_stiffness

// Live calibration of the stiffness model against the rig's encoders and its identified natural
// frequencies, free of ROS and of any clock: docs/calibration.md "1. Measured TE" to "4. Outputs
// and confidence bands", and "Natural frequencies". Allocation-free per reading; per window and per
// identification only fixed-size Eigen and the supports' preallocated solutions.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "drivetrain_stiffness/calibration/calibration_report.hpp"
#include "drivetrain_stiffness/calibration/model_error_scale.hpp"
#include "drivetrain_stiffness/calibration/order_regression.hpp"
#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/calibration/window_accumulator.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

class StiffnessEstimator;

/// The calibrated stiffness and natural frequencies at an operating point, 95 % bounds.
struct CalibrationBands {
  /// A window or a record of natural frequencies updated the parameters (else: the prior's bounds).
  bool calibrated = false;
  double mesh_stiffness = 0.0, mesh_stiffness_low = 0.0,
         mesh_stiffness_high = 0.0;  ///< [N/m] period mean
  std::array<double, 2> bearing_stiffness{}, bearing_stiffness_low{},
      bearing_stiffness_high{};  ///< [N/m] per shaft
  std::array<double, 3> natural_frequency{}, natural_frequency_low{},
      natural_frequency_high{};  ///< [Hz]
};

/// An identified natural frequency matched to the model's mode `mode` (0..2, modalAnalysis's order,
/// by natural frequency).
struct ModalFrequency {
  int mode = 0;
  double frequency = 0.0;      ///< [Hz]
  double frequency_std = 0.0;  ///< [Hz] its standard deviation (> 0)
};

class Calibrator {
 public:
  /// The priors and rules of the rig's calibration block; `mesh`: the rig's own table, shared.
  /// Throws InvalidInput for a rig without a valid calibration block.
  explicit Calibrator(std::shared_ptr<const RigConfig> rig,
                      std::shared_ptr<const AntiBacklashMesh> mesh = nullptr);
  /// The same on a copy of `rig`.
  explicit Calibrator(const RigConfig& rig);

  /// What a reading produced (bit flags).
  enum : int { kNothing = 0, kSample = 1, kWindow = 2 };
  /// One reading at t [s]: unwrapped angles [rad], mesh phase [-], pinion speed [rad/s], held
  /// torque [N·m]; fills `sample` when it returns kSample.
  int reading(double t, double pinion, double gear, double phase, double speed, double torque,
              const StiffnessEstimator& supports, MeasuredTeSample& sample);
  /// The readings broke off: drops the open window.
  void interrupt();
  const CalibrationEstimate& estimate() const { return estimate_; }
  /// What the calibration has seen, the open window as a stretch. Allocation-free.
  CalibrationProgress progress() const;
  /// One record's identified frequencies at pinion torque [N·m], t [s] the record's end: one
  /// update of the same state as the TE windows (no baseline needed); each `mode` indexes modes()
  /// at the current estimate. Returns kUpdated, kGated (NIS over the gate), or kNone (no usable
  /// frequency). Throws InvalidInput naming a mode out of range or given twice, a frequency or std
  /// that is not positive and finite, more than 3 frequencies, or a non-finite t or torque.
  /// Allocation-free.
  WindowOutcome modalUpdate(double t, const ModalFrequency* frequencies, std::size_t count,
                            double torque, const StiffnessEstimator& supports);
  /// The calibrated model's three modes (with shapes) at pinion torque [N·m]: modalAnalysis of the
  /// current estimate (bearing scales times the supports' unit stiffness, the mesh's period-mean
  /// stiffness at that torque).
  std::array<Mode, 3> modes(double torque, const StiffnessEstimator& supports) const;
  /// Why no window has updated the estimate, one sentence with the numbers (docs/calibration.md
  /// "When no window updates"), led by the count of records of natural frequencies that did; empty
  /// once a window has. Allocates.
  std::string waitingReason() const;
  const RigConfig& rig() const { return *rig_; }
  const StaticTeModel& model() const { return model_; }
  const CalibrationVector& parameters() const { return estimate_.value; }
  const CalibrationMatrix& covariance() const { return covariance_; }
  /// The filter's own covariance, under the configured model-error allowance.
  CalibrationMatrix filterCovariance() const;
  /// The calibrated stiffness at pinion torque [N·m] and, `with_modes`, the natural frequencies.
  /// Allocation-free.
  CalibrationBands bands(double torque, const StiffnessEstimator& supports, bool with_modes) const;

 private:
  /// The spanning window's outcome, and the baseline or the update it makes.
  void closeWindow(const StiffnessEstimator& supports);
  void update(const FeatureVector& z, const FeatureVector& z_std, double torque);
  /// The features' Jacobian at state p and torque [N·m]: closed-form columns for the offset and the
  /// bearing compliances, central differences for the mesh scale and T_p; held parameters 0.
  void jacobian(const CalibrationVector& p, double torque, ModelErrorScale::FeatureRows& H) const;
  /// The iterated EKF's posterior mode from state_ (at most four relinearisations); H and K are
  /// those of the last iteration.
  CalibrationVector iteratedUpdate(const CalibrationMatrix& prior,
                                   const Eigen::Matrix<double, kFeatureSize, kFeatureSize>& R,
                                   const FeatureVector& z, double torque,
                                   ModelErrorScale::FeatureRows& H, ModelErrorScale::Gain& K) const;
  /// Clamps a state to the physical bounds: scales in [0.05, 19.9], T_p >= 0.
  static void bound(CalibrationVector& state);
  /// The random walk since the last update at t [s] (docs/calibration.md "3. The estimator").
  CalibrationMatrix processNoise(double t) const;
  void outputs(double torque, const StiffnessEstimator& supports);
  /// sqrt(g' P g), g the central-difference gradient of f over the parameters set in depends_on.
  template <typename F>
  double spreadOf(F&& f, std::uint32_t depends_on = ~0u) const;
  FeatureVector predict(const CalibrationVector& p, double torque) const;
  /// Each shaft's bearing stiffness at scale 1 [N/m]: the supports' radial stiffness at their
  /// current load over their configured stiffness_scale.
  std::array<double, 2> unitBearingStiffness(const StiffnessEstimator& supports) const;
  /// The model's modes at parameters p, pinion torque [N·m] and unit bearing stiffness [N/m].
  std::array<Mode, 3> modesAt(const CalibrationVector& p, double torque,
                              const std::array<double, 2>& unit,
                              const StiffnessEstimator& supports) const;

  std::shared_ptr<const RigConfig> rig_;
  const CalibrationConfig& config_;  ///< rig_->calibration
  StaticTeModel model_;
  WindowAccumulator windows_;

  /// The filter's state: each bearing scale s as its compliance factor c = 1/s (docs/calibration.md
  /// "3. The estimator").
  CalibrationVector state_ = CalibrationVector::Zero(),
                    state_prior_std_ = CalibrationVector::Zero();
  /// The drawing's spread in the state's coordinates.
  CalibrationVector state_reference_std_ = CalibrationVector::Zero();
  CalibrationMatrix state_covariance_ = CalibrationMatrix::Zero();
  CalibrationMatrix covariance_ = CalibrationMatrix::Zero();  ///< of the parameters
  ModelErrorScale model_error_;
  /// State to parameters (c -> 1/c), and that map's Jacobian.
  static CalibrationVector toParameters(const CalibrationVector& state);
  static CalibrationMatrix parameterJacobian(const CalibrationVector& state);
  CalibrationEstimate estimate_;
  CalibrationReport report_;
  /// Records that carried each mode's frequency (docs/calibration.md "Natural frequencies").
  std::array<std::uint32_t, 3> modal_count_{};
  double last_update_t_ = 0.0;
  bool has_update_t_ = false;
  std::array<double, 2> scratch_{};
};

}  // namespace drivetrain_stiffness

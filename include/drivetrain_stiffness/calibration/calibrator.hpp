// Live calibration of the stiffness model against the rig's encoders and its identified natural
// frequencies, free of ROS and of any clock: docs/calibration.md "1. Measured TE" to "4. Outputs
// and confidence bands", and "Natural frequencies". Allocation-free per reading; per window and per
// identification only fixed-size Eigen and the supports' preallocated solutions.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "drivetrain_stiffness/calibration/calibration_estimator.hpp"
#include "drivetrain_stiffness/calibration/calibration_report.hpp"
#include "drivetrain_stiffness/calibration/model_error_scale.hpp"
#include "drivetrain_stiffness/calibration/order_regression.hpp"
#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/calibration/window_accumulator.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
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
  const CalibrationEstimate& estimate() const { return estimate_; }  ///< the last update's state
  /// What the calibration has seen, the open window as a stretch. Allocation-free.
  CalibrationProgress progress() const;
  /// One record's identified frequencies at pinion torque [N·m], t [s] the record's end: one
  /// update of the TE windows' state (no baseline needed); each `mode` indexes modes() at the
  /// estimate. Returns kUpdated, kGated (NIS over the gate), or kNone (no usable frequency). Throws
  /// InvalidInput naming a mode out of range or given twice, a frequency or std that is not
  /// positive and finite, more than 3 frequencies, or a non-finite t or torque. Allocation-free.
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
  const RigConfig& rig() const { return *rig_; }           ///< the calibrated rig
  const StaticTeModel& teModel() const { return model_; }  ///< the windows' static TE model
  const CalibrationVector& parameters() const { return estimate_.value; }  ///< the estimate's value
  /// The parameters' reported covariance (under the model error the windows show).
  const CalibrationMatrix& covariance() const { return covariance_; }
  /// The filter's own covariance, under the configured model-error allowance.
  CalibrationMatrix filterCovariance() const { return estimator_.filterCovariance(); }
  /// The calibrated stiffness at pinion torque [N·m] and, `with_modes`, the natural frequencies.
  /// Allocation-free.
  CalibrationBands bands(double torque, const StiffnessEstimator& supports, bool with_modes) const;

 private:
  /// The spanning window's outcome, and the baseline or the update it makes.
  void closeWindow(const StiffnessEstimator& supports);
  /// The filter's update by the closed window's features z (std z_std) at torque [N·m].
  void update(const FeatureVector& z, const FeatureVector& z_std, double torque);
  /// The estimate's parameters, covariance, stiffness and modes at torque [N·m] from the filter.
  void outputs(double torque, const StiffnessEstimator& supports);
  /// sqrt(g' P g), g the central-difference gradient of f over the parameters set in depends_on.
  template <typename F>
  double spreadOf(F&& f, std::uint32_t depends_on = ~0u) const;

  std::shared_ptr<const RigConfig> rig_;
  const CalibrationConfig& config_;  ///< rig_->calibration
  StaticTeModel model_;
  WindowAccumulator windows_;
  CalibrationEstimator estimator_;
  CalibrationReport report_;
  CalibrationEstimate estimate_;
  CalibrationMatrix covariance_ = CalibrationMatrix::Zero();  ///< of the parameters
  std::array<double, 2> scratch_{};
};

}  // namespace drivetrain_stiffness

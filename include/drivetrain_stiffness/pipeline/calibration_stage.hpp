// The calibration stage (the calibration rule, docs/ros_api.md "Time and input rules"): each
// accepted encoder reading with the gear joint to the live Calibrator with the torque held at its
// stamp, its outputs to the sink, its failures counted; and the stiffness and resonance bands the
// sink is handed (the calibration's, or the drawing's model with bounds of zero width). ROS-free.
#pragma once

#include <memory>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

class CalibrationStage {
 public:
  /// Calibrates when `enabled` and the rig has a calibration and a dynamics block (none otherwise).
  /// Keeps references to `estimator` (the bearing models at their current settings; its mesh
  /// table is shared) and `counters` (measured_te_out, calibration_out, calibration_errors,
  /// last_event).
  CalibrationStage(std::shared_ptr<const RigConfig> rig, const StiffnessEstimator& estimator, bool enabled,
                   PipelineCounters& counters);
  /// The live calibration, or null.
  const Calibrator* calibrator() const { return calibrator_.get(); }
  /// The readings broke off: the open window is dropped.
  void interrupt();
  /// One accepted reading at `stamp`: unwrapped pinion and gear angles [rad], mesh phase [-],
  /// pinion speed [rad/s], held torque [N*m]; `continuous`: it follows the last one without a
  /// break (else a new window starts). A sample and a closed window go to the sink; the library's
  /// own errors (a refused message among them) are counted and drop the window. Needs calibrator().
  void reading(Stamp stamp, double pinion, double gear, double phase, double speed, double held_torque, bool continuous,
               PipelineSink& sink);
  /// The bands of PipelineSink::stiffness for `estimate`.
  CalibrationBands stiffnessBands(const StiffnessEstimate& estimate) const;
  /// The bands of PipelineSink::resonance at the estimator's current torque.
  CalibrationBands resonanceBands(const ResonanceEstimate& estimate) const;

 private:
  const StiffnessEstimator& estimator_;
  PipelineCounters& counters_;
  std::unique_ptr<Calibrator> calibrator_;
  MeasuredTeSample measured_te_;  ///< the calibrator's per-reading output (reused: no allocation)
};

}  // namespace drivetrain_stiffness

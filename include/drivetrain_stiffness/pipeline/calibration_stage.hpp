// The calibration stage (the calibration rule, docs/ros_api.md): readings to the live Calibrator,
// its outputs to the sink, and the bands for the stiffness and resonance outputs.
#pragma once

#include <memory>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

class CalibrationStage {
 public:
  /// Calibrates when `enabled` and the rig has calibration and dynamics blocks. Keeps a reference
  /// to `estimator`.
  CalibrationStage(std::shared_ptr<const RigConfig> rig, const StiffnessEstimator& estimator,
                   bool enabled);
  /// The live calibration, or null.
  const Calibrator* calibrator() const { return calibrator_.get(); }
  /// The readings broke off: the open window is dropped.
  void interrupt();
  /// One reading: angles [rad], mesh phase [-], speed [rad/s], held torque [N*m]; not `continuous`:
  /// a new window. An Error is counted and drops the window. Needs calibrator().
  void reading(Stamp stamp, double pinion, double gear, double phase, double speed,
               double held_torque, bool continuous, PipelineSink& sink);
  /// One record's identified frequencies at held torque [N*m]: one update of the calibration,
  /// published unless no frequency was usable; an Error is counted. Without a calibrator: ignored.
  void modal(Stamp stamp, const ModalFrequency* frequencies, std::size_t count, double torque,
             PipelineSink& sink);
  /// PipelineSink::stiffness's bands.
  CalibrationBands stiffnessBands(const StiffnessEstimate& estimate) const;
  /// PipelineSink::resonance's bands, at the current torque.
  CalibrationBands resonanceBands(const ResonanceEstimate& estimate) const;
  const CalibrationCounters& counters() const { return counters_; }
  /// The last error, with its reason.
  const EventLog& events() const { return events_; }

 private:
  const StiffnessEstimator& estimator_;
  CalibrationCounters counters_;
  EventLog events_;
  std::unique_ptr<Calibrator> calibrator_;
  MeasuredTeSample measured_te_;
};

}  // namespace drivetrain_stiffness

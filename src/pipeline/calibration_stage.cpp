#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"

#include <string>

namespace drivetrain_stiffness {

CalibrationStage::CalibrationStage(std::shared_ptr<const RigConfig> rig,
                                   const StiffnessEstimator& estimator, bool enabled)
    : estimator_(estimator) {
  // One mesh table for the rig: the stiffness estimator's, shared read only.
  if (enabled && rig->calibration.present && rig->dynamics.present) {
    calibrator_ = std::make_unique<Calibrator>(rig, estimator.sharedMesh());
  }
}

void CalibrationStage::interrupt() {
  if (calibrator_) calibrator_->interrupt();
}

void CalibrationStage::reading(Stamp stamp, double pinion, double gear, double phase, double speed,
                               double held_torque, bool continuous, PipelineSink& sink) {
  if (!continuous) calibrator_->interrupt();
  try {
    const int out = calibrator_->reading(stamp.toSec(), pinion, gear, phase, speed, held_torque,
                                         estimator_, measured_te_);
    // Counted once the sink took it: a message the sink refuses (non-finite) is an error, not both.
    if (out & Calibrator::kSample) {
      sink.measuredTe(stamp, measured_te_);
      ++counters_.measured_te_out;
    }
    if (out & Calibrator::kWindow) {
      sink.calibration(stamp, calibrator_->estimate());
      ++counters_.calibration_out;
    }
  } catch (const Error& e) {
    ++counters_.calibration_errors;
    events_.record(std::string("calibration: ") + e.what());
    calibrator_->interrupt();
  }
}

void CalibrationStage::modal(Stamp stamp, const ModalFrequency* frequencies, std::size_t count,
                             double torque, PipelineSink& sink) {
  if (!calibrator_) return;
  try {
    const WindowOutcome outcome =
        calibrator_->modalUpdate(stamp.toSec(), frequencies, count, torque, estimator_);
    if (outcome != WindowOutcome::kNone) {
      sink.calibration(stamp, calibrator_->estimate());
      ++counters_.calibration_out;
    }
  } catch (const Error& e) {
    ++counters_.calibration_errors;
    events_.record(std::string("calibration: ") + e.what());
  }
}

CalibrationBands CalibrationStage::stiffnessBands(const StiffnessEstimate& estimate) const {
  if (calibrator_) return calibrator_->bands(estimate.torque, estimator_, false);
  CalibrationBands b;  // no calibration: the drawing's model, bounds of zero width
  b.mesh_stiffness = b.mesh_stiffness_low = b.mesh_stiffness_high = estimate.mesh.mean;
  b.bearing_stiffness = b.bearing_stiffness_low = b.bearing_stiffness_high =
      estimator_.shaftRadialStiffness();
  return b;
}

CalibrationBands CalibrationStage::resonanceBands(const ResonanceEstimate& estimate) const {
  if (calibrator_) return calibrator_->bands(estimator_.current().torque, estimator_, true);
  CalibrationBands b;  // no calibration: the drawing's frequencies, bounds of zero width
  for (std::size_t i = 0; i < estimate.modes.size(); ++i) {
    b.natural_frequency[i] = b.natural_frequency_low[i] = b.natural_frequency_high[i] =
        estimate.modes[i].natural_frequency;
  }
  return b;
}

}  // namespace drivetrain_stiffness

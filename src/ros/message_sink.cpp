#include "drivetrain_stiffness/ros/message_sink.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

double nominalMeshForce(const RigConfig& rig) {
  const double torque = rig.dynamics.present ? rig.dynamics.torque : 0.1;  // seed 000 Table 1: 0.1 N*m
  return std::abs(meshForce(rig.gears, 0, torque));
}

}  // namespace

MessageSink::MessageSink(const RigPipeline& pipeline, const OutputSettings& settings)
    : pipeline_(pipeline),
      settings_(settings),
      visualizer_(pipeline.estimator().mesh().geometry(), pipeline.rig().gears.face_width, nominalMeshForce(pipeline.rig()),
                  settings.frames, pipeline.settings().exaggeration) {}

void MessageSink::stiffness(Stamp stamp, const StiffnessEstimate& estimate) {
  fillStiffnessMsg(stamp, settings_.frames.rig, estimate, stiffness_msg_);
  fillStiffnessBands(stiffnessBands(estimate), stiffness_msg_);
  stiffness_msg_.header.seq = stiffness_seq_++;
  emitStiffness(stiffness_msg_);
}

void MessageSink::transmissionError(Stamp stamp, const DynamicsSample& sample) {
  drivetrain_stiffness::TransmissionError te = toTransmissionErrorMsg(stamp, settings_.frames.pinion, sample);
  te.header.seq = te_seq_++;
  emitTransmissionError(te);
  const RuntimeSettings& run = pipeline_.settings();
  if (run.tf_rate <= 0.0) return;
  // Decided on sample stamps, so a replay draws the same frames as the live node.
  if (last_tf_ && !(stamp < *last_tf_) && secondsBetween(stamp, *last_tf_) < 1.0 / run.tf_rate) return;
  last_tf_ = stamp;
  if (run.exaggeration != visualizer_.exaggeration()) visualizer_.setExaggeration(run.exaggeration);
  emitTransforms(visualizer_.transforms(toRosTime(stamp), sample, pipeline_.pinionAngle(stamp)));
  emitMarkers(visualizer_.markers(toRosTime(stamp), sample, pipeline_.lastResonance()));
}

void MessageSink::spectrum(Stamp stamp, const SlidingSpectrum& spectrum) {
  emitSpectrum(toSpectralPeaksMsg(stamp, settings_.frames.pinion, spectrum));
}

void MessageSink::resonance(Stamp stamp, const ResonanceEstimate& estimate) {
  drivetrain_stiffness::Resonance m = toResonanceMsg(stamp, settings_.frames.rig, estimate);
  CalibrationBands b;
  if (const Calibrator* c = pipeline_.calibrator()) {
    b = c->bands(pipeline_.estimator().current().torque, pipeline_.estimator(), true);
  } else {  // no calibration: the drawing's frequencies, bounds of zero width
    for (int i = 0; i < 3; ++i) {
      b.natural_frequency[i] = b.natural_frequency_low[i] = b.natural_frequency_high[i] = estimate.modes[i].natural_frequency;
    }
  }
  fillResonanceBands(b, m);
  emitResonance(m);
}

CalibrationBands MessageSink::stiffnessBands(const StiffnessEstimate& estimate) const {
  if (const Calibrator* c = pipeline_.calibrator()) return c->bands(estimate.torque, pipeline_.estimator(), false);
  // No calibration: the drawing's model, bounds of zero width.
  CalibrationBands b;
  b.mesh_stiffness = b.mesh_stiffness_low = b.mesh_stiffness_high = estimate.mesh.mean;
  const std::array<double, 2> k = pipeline_.estimator().shaftRadialStiffness();
  b.bearing_stiffness = b.bearing_stiffness_low = b.bearing_stiffness_high = k;
  return b;
}

void MessageSink::measuredTe(Stamp stamp, const MeasuredTeSample& sample) {
  drivetrain_stiffness::MeasuredTe m = toMeasuredTeMsg(stamp, settings_.frames.pinion, sample);
  m.header.seq = measured_te_seq_++;
  emitMeasuredTe(m);
}

void MessageSink::calibration(Stamp stamp, const CalibrationEstimate& estimate) {
  drivetrain_stiffness::Calibration m = toCalibrationMsg(stamp, settings_.frames.rig, estimate);
  m.header.seq = calibration_seq_++;
  emitCalibration(m);
}

void MessageSink::meshPeriod(Stamp stamp, const MeshPeriodStatistics& stats) {
  drivetrain_stiffness::MeshPeriodStats m = toMeshPeriodStatsMsg(stamp, settings_.frames.pinion, stats);
  m.header.seq = mesh_period_seq_++;
  emitMeshPeriodStats(m);
}

}  // namespace drivetrain_stiffness

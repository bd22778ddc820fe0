#include "drivetrain_stiffness/ros/message_sink.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

double nominalMeshForce(const RigConfig& rig) {
  const double torque =
      rig.dynamics.present ? rig.dynamics.torque : 0.1;  // seed 000 Table 1: 0.1 N*m
  return std::abs(meshForce(rig.gears, 0, torque));
}

}  // namespace

MessageSink::MessageSink(const RigPipeline& pipeline, const OutputSettings& settings)
    : settings_(settings),
      tf_rate_(pipeline.settings().tf_rate),
      exaggeration_(pipeline.settings().exaggeration),
      visualizer_(pipeline.estimator().mesh().geometry(), pipeline.rig().gears.face_width,
                  nominalMeshForce(pipeline.rig()), settings.frames,
                  pipeline.settings().exaggeration) {}

void MessageSink::apply(const RuntimeSettings& settings) {
  tf_rate_ = settings.tf_rate;
  exaggeration_ = settings.exaggeration;
}

void MessageSink::stiffness(Stamp stamp, const StiffnessEstimate& estimate,
                            const CalibrationBands& bands) {
  fillStiffnessMsg(stamp, settings_.frames.rig, estimate, stiffness_msg_);
  fillStiffnessBands(bands, stiffness_msg_);
  stiffness_msg_.header.seq = stiffness_seq_++;
  emitStiffness(stiffness_msg_);
}

void MessageSink::transmissionError(Stamp stamp, const DynamicsSample& sample,
                                    const SampleContext& context) {
  drivetrain_stiffness::TransmissionError te =
      toTransmissionErrorMsg(stamp, settings_.frames.pinion, sample);
  te.header.seq = te_seq_++;
  emitTransmissionError(te);
  if (tf_rate_ <= 0.0) return;
  // Decided on sample stamps, so a replay draws the same frames as the live node.
  if (last_tf_ && !(stamp < *last_tf_) && secondsBetween(stamp, *last_tf_) < 1.0 / tf_rate_) return;
  last_tf_ = stamp;
  if (exaggeration_ != visualizer_.exaggeration()) visualizer_.setExaggeration(exaggeration_);
  emitTransforms(visualizer_.transforms(toRosTime(stamp), sample, context.pinion_angle));
  emitMarkers(visualizer_.markers(toRosTime(stamp), sample, context.resonance));
}

void MessageSink::spectrum(Stamp stamp, const SpectrumPeaks& peaks) {
  emitSpectrum(toSpectralPeaksMsg(stamp, settings_.frames.pinion, peaks));
}

void MessageSink::resonance(Stamp stamp, const ResonanceEstimate& estimate,
                            const CalibrationBands& bands) {
  drivetrain_stiffness::Resonance m = toResonanceMsg(stamp, settings_.frames.rig, estimate);
  fillResonanceBands(bands, m);
  emitResonance(m);
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

void MessageSink::modalIdentification(Stamp stamp, const ModalReport& report) {
  drivetrain_stiffness::ModalIdentification m =
      toModalIdentificationMsg(stamp, settings_.frames.pinion, report);
  m.header.seq = modal_seq_++;
  emitModalIdentification(m);
}

void MessageSink::meshPeriod(Stamp stamp, const MeshPeriodStatistics& stats) {
  drivetrain_stiffness::MeshPeriodStats m =
      toMeshPeriodStatsMsg(stamp, settings_.frames.pinion, stats);
  m.header.seq = mesh_period_seq_++;
  emitMeshPeriodStats(m);
}

}  // namespace drivetrain_stiffness

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
                  settings.frames, settings.exaggeration) {
  setTfRate(settings.tf_rate);
}

void MessageSink::setExaggeration(double exaggeration) {
  visualizer_.setExaggeration(exaggeration);
  settings_.exaggeration = exaggeration;
}

void MessageSink::setTfRate(double hz) {
  requireNonNegative("tf_rate", hz);
  settings_.tf_rate = hz;
}

void MessageSink::stiffness(Stamp stamp, const StiffnessEstimate& estimate) {
  emitStiffness(toStiffnessMsg(stamp, settings_.frames.rig, estimate));
}

void MessageSink::transmissionError(const DynamicsSample& sample) {
  emitTransmissionError(toTransmissionErrorMsg(settings_.frames.pinion, sample));
  if (settings_.tf_rate <= 0.0) return;
  if (last_tf_t_ && sample.t >= *last_tf_t_ && sample.t - *last_tf_t_ < 1.0 / settings_.tf_rate) return;
  last_tf_t_ = sample.t;
  const Stamp stamp{static_cast<std::int64_t>(std::llround(sample.t * 1e9))};
  emitTransforms(visualizer_.transforms(sample, pipeline_.pinionAngle(stamp)));
  emitMarkers(visualizer_.markers(sample, pipeline_.lastResonance()));
}

void MessageSink::spectrum(double t, const SlidingSpectrum& spectrum) {
  emitSpectrum(toSpectralPeaksMsg(t, settings_.frames.pinion, spectrum));
}

void MessageSink::resonance(Stamp stamp, const ResonanceEstimate& estimate) {
  emitResonance(toResonanceMsg(stamp, settings_.frames.rig, estimate));
}

}  // namespace drivetrain_stiffness

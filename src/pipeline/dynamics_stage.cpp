#include "drivetrain_stiffness/pipeline/dynamics_stage.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

DynamicsStage::DynamicsStage(std::shared_ptr<const RigConfig> rig,
                             const StiffnessEstimator& estimator, const PipelineOptions& options,
                             Fidelity fidelity, PhaseSource& phase, PipelineCounters& counters)
    : estimator_(estimator),
      phase_(phase),
      counters_(counters),
      model_(std::move(rig), estimator.shaftRadialStiffness(), options.output_rate,
             estimator.sharedMesh()),
      max_gap_(options.max_gap) {
  model_.setFidelity(fidelity);
  model_.setMotionSlices(options.motion_slices);
}

void DynamicsStage::error(const std::string& where, const Error& e) {
  ++counters_.dynamics_errors;
  counters_.last_event = where + ": " + e.what();
}

void DynamicsStage::stop() {
  model_.stop();
  for (SampleConsumer* c : consumers_) c->restart();  // nothing before the stop continues after it
}

void DynamicsStage::restart(Stamp stamp, double torque) {
  epoch_ = stamp;
  model_.reset(0.0, torque);
  for (SampleConsumer* c : consumers_) c->restart();  // a new spectrum window, no mesh periods
  phase_.setOrigin(stamp);  // the stiffness message's mesh phase restarts with the dynamics
  followAnchor(stamp);      // measured motion: the dynamics start at the measured phase
}

void DynamicsStage::reset() {
  // The model restarts at the next torque input (its reset needs its time), with the bearing
  // stiffness of the configured preloads: taken up only if it moved by more than 1 %, as always.
  stop();
  try {
    model_.setBearingStiffness(estimator_.shaftRadialStiffness());
  } catch (const Error& e) {
    error("dynamics", e);
  }
}

void DynamicsStage::stopAfterGap(Stamp stamp) {
  if (!model_.started()) return;
  const double gap = secondsBetween(stamp, epoch_) - model_.time();
  if (!(gap > max_gap_)) return;
  ++counters_.gap_restarts;
  counters_.last_event =
      "input gap of " + formatValue(gap) + " s (more than ~max_gap): dynamics restarted";
  stop();
}

bool DynamicsStage::advanceTo(Stamp stamp, PipelineSink& sink) {
  if (!model_.started()) return false;
  const double t = secondsBetween(stamp, epoch_);
  // Past it already (another stream), or a gap the gap rule restarts at the next torque input.
  if (t <= model_.time() || t - model_.time() > max_gap_) return false;
  try {
    emitUpTo(t, sink);
  } catch (const Error& e) {
    error("dynamics (restarted at the next torque input)", e);
    stop();
    return false;
  }
  return true;
}

void DynamicsStage::emitUpTo(double t, PipelineSink& sink) {
  const double from = model_.time();
  // The motion is held over one advance: its mesh frequency unwraps the phase between samples.
  // A member, not a capture: the lambda must stay within std::function's small buffer (two
  // pointers), or every advance allocates (allocation_tests).
  advance_mesh_frequency_ = model_.meshFrequency();
  // The time integrated counts whether the advance ends or throws (a throw passes on untouched).
  struct CountSimulated {
    const DynamicsEstimator& dynamics;
    double from;
    double& simulated;
    ~CountSimulated() { simulated += dynamics.time() - from; }
  } count{model_, from, counters_.simulated_s};
  model_.advanceTo(t, [this, &sink](const DynamicsSample& relative) {
    DynamicsSample s = relative;
    const Stamp sample_stamp{epoch_.ns + std::llround(relative.t * 1e9)};
    s.t = sample_stamp.toSec();
    for (SampleConsumer* c : consumers_) c->sample(sample_stamp, s, advance_mesh_frequency_, sink);
  });
}

bool DynamicsStage::takeTorque(Stamp stamp, double torque, PipelineSink& sink) {
  std::optional<double> at;  // the stamp on the model's clock, once the model runs up to it
  try {
    // The gap rule: a paused rig restarts the model at this input instead of integrating the gap.
    stopAfterGap(stamp);
    if (!model_.started()) {
      restart(stamp, torque);
      return false;
    }
    const double t = secondsBetween(stamp, epoch_);
    // Else another stream took the model past this stamp: the torque applies from there.
    if (t > model_.time()) emitUpTo(t, sink);
    at = t;
  } catch (const Error& e) {
    // The state stays at its last good sample and every later input would fail the same way:
    // restart the model here (counted), as after a gap.
    error("dynamics (restarted at this input)", e);
    try {
      restart(stamp, torque);
    } catch (const Error& again) {
      error("dynamics", again);
    }
  }
  try {
    model_.setTorque(torque,
                     at);  // the new torque holds from its stamp on, whatever happened above
  } catch (const Error& e) {
    error("dynamics", e);
  }
  return true;
}

void DynamicsStage::takeBearingStiffness(Stamp stamp, PipelineSink& sink) {
  // Taken up only when it moved by more than 1 %, at the input's own stamp. After a gap the model
  // stops first and restarts at the next torque input with it: the stiffness belongs after the
  // gap, not at the last input before it.
  stopAfterGap(stamp);
  const bool advanced = advanceTo(stamp, sink);
  try {
    std::optional<double> at;
    if (model_.started()) at = advanced ? secondsBetween(stamp, epoch_) : model_.time();
    model_.setBearingStiffness(estimator_.shaftRadialStiffness(), at);
  } catch (const Error& e) {
    error("dynamics", e);
  }
}

void DynamicsStage::followAnchor(Stamp stamp) {
  if (!model_.started() || !phase_.anchor()) return;
  try {
    // Another stream may have taken the model past this stamp: the motion applies from there.
    const double t = std::max(secondsBetween(stamp, epoch_), model_.time());
    const Stamp at{epoch_.ns + std::llround(t * 1e9)};
    model_.followMotion(t, phase_.meshTurns(phase_.pinionAngle(at)),
                        phase_.meshTurns(phase_.anchor()->speed));
  } catch (const Error& e) {
    error("dynamics", e);
  }
}

}  // namespace drivetrain_stiffness

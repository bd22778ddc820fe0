#include "drivetrain_stiffness/pipeline/dynamics_stage.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

DynamicsStage::DynamicsStage(std::shared_ptr<const RigConfig> rig,
                             const StiffnessEstimator& stiffness, const PipelineOptions& options,
                             Fidelity fidelity)
    : stiffness_(stiffness),
      dynamics_(std::move(rig), stiffness.shaftRadialStiffness(), options.output_rate,
                stiffness.sharedMesh()),
      max_gap_(options.max_gap) {
  dynamics_.setFidelity(fidelity);
  dynamics_.setMotionSlices(options.motion_slices);
}

void DynamicsStage::error(const std::string& where, const Error& e) {
  ++counters_.model_errors;
  events_.record(where + ": " + e.what());
}

void DynamicsStage::stop() {
  dynamics_.stop();
  for (SampleConsumer* c : consumers_) c->restart();  // nothing before the stop continues after it
}

void DynamicsStage::restart(Stamp stamp, double torque) {
  epoch_ = stamp;
  dynamics_.reset(0.0, torque);
  for (SampleConsumer* c : consumers_) c->restart();  // a new spectrum window, no mesh periods
}

void DynamicsStage::reset() {
  // The model restarts at the next torque input (its reset needs its time), with the bearing
  // stiffness of the configured preloads: taken up only if it moved by more than 1 %.
  stop();
  try {
    dynamics_.setBearingStiffness(stiffness_.shaftRadialStiffness());
  } catch (const Error& e) {
    error("dynamics", e);
  }
}

void DynamicsStage::stopAfterGap(Stamp stamp) {
  if (!dynamics_.started()) return;
  const double gap = secondsBetween(stamp, epoch_) - dynamics_.time();
  if (!(gap > max_gap_)) return;
  ++counters_.gap_restarts;
  events_.record("input gap of " + formatValue(gap) +
                 " s (more than ~max_gap): dynamics restarted");
  stop();
}

Advance DynamicsStage::advanceTo(Stamp stamp, PipelineSink& sink) {
  if (!dynamics_.started()) return Advance::kStopped;
  const double t = secondsBetween(stamp, epoch_);
  if (t <= dynamics_.time()) return Advance::kAlreadyPast;
  if (t - dynamics_.time() > max_gap_) return Advance::kGap;
  try {
    emitUpTo(t, sink);
  } catch (const Error& e) {
    error("dynamics (restarted at the next torque input)", e);
    stop();
    return Advance::kFailed;
  }
  return Advance::kAdvanced;
}

void DynamicsStage::emitUpTo(double t, PipelineSink& sink) {
  const double from = dynamics_.time();
  // The motion is held over one advance: its mesh frequency unwraps the phase between samples.
  // A member, not a capture: the lambda must stay within std::function's small buffer (two
  // pointers), or every advance allocates (allocation_tests).
  advance_mesh_frequency_ = dynamics_.meshFrequency();
  // The time integrated counts whether the advance ends or throws (a throw passes on untouched).
  struct CountSimulated {
    const DynamicsEstimator& dynamics;
    double from;
    double& simulated;
    ~CountSimulated() { simulated += dynamics.time() - from; }
  } count{dynamics_, from, counters_.simulated_s};
  dynamics_.advanceTo(t, [this, &sink](const DynamicsSample& relative) {
    DynamicsSample s = relative;
    const Stamp sample_stamp{epoch_.ns + std::llround(relative.t * 1e9)};
    s.t = sample_stamp.toSec();
    for (SampleConsumer* c : consumers_) c->sample(sample_stamp, s, advance_mesh_frequency_, sink);
  });
}

TorqueTaken DynamicsStage::takeTorque(Stamp stamp, double torque) {
  if (!dynamics_.started()) {
    // The gap rule, a failure or a reset stopped it (or it never ran): it restarts at this input
    // instead of integrating what it missed.
    try {
      restart(stamp, torque);
    } catch (const Error& e) {
      error("dynamics", e);
    }
    return TorqueTaken::kRestarted;
  }
  try {
    // From its stamp on; where another stream took the model past it, from the model's time.
    dynamics_.setTorque(torque, secondsBetween(stamp, epoch_));
  } catch (const Error& e) {
    error("dynamics", e);
  }
  return TorqueTaken::kHeld;
}

void DynamicsStage::takeBearingStiffness(Stamp stamp, Advance advanced) {
  // Taken up only when it moved by more than 1 %, at the input's own stamp. A stopped model
  // restarts at the next torque input with it: the stiffness belongs after a gap, not at the last
  // input before it.
  try {
    std::optional<double> at;
    if (dynamics_.started()) {
      at = advanced == Advance::kAdvanced ? secondsBetween(stamp, epoch_) : dynamics_.time();
    }
    dynamics_.setBearingStiffness(stiffness_.shaftRadialStiffness(), at);
  } catch (const Error& e) {
    error("dynamics", e);
  }
}

std::optional<DynamicsStage::Moment> DynamicsStage::momentAtOrAfter(Stamp stamp) const {
  if (!dynamics_.started()) return std::nullopt;
  const double t = std::max(secondsBetween(stamp, epoch_), dynamics_.time());
  return Moment{t, Stamp{epoch_.ns + std::llround(t * 1e9)}};
}

void DynamicsStage::followMotion(const Moment& at, double mesh_turns, double mesh_frequency) {
  try {
    dynamics_.followMotion(at.t, mesh_turns, mesh_frequency);
  } catch (const Error& e) {
    error("dynamics", e);
  }
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
const char* toString(InputOutcome outcome) {
  switch (outcome) {
    case InputOutcome::kAccepted: return "accepted";
    case InputOutcome::kZeroStamp: return "zero stamp";
    case InputOutcome::kOutOfOrder: return "out of order";
    case InputOutcome::kInvalidValue: return "invalid value";
    case InputOutcome::kUnreachableLoad: return "unreachable load";
    case InputOutcome::kWrongFrame: return "wrong frame";
    case InputOutcome::kStampRange: return "stamp outside ROS time";
  }
  return "?";
}

RigPipeline::RigPipeline(const RigConfig& rig, const PipelineOptions& options)
    : RigPipeline(rig, options, RuntimeSettings::forRig(rig)) {}

namespace {
/// The rig as the pipeline runs it, built once and shared read only by the stiffness estimator, the
/// dynamics and the calibration: the gearbox with the start-up damping ratios of the run-time
/// settings and, with dynamics, the nominal speed of the options.
std::shared_ptr<const RigConfig> runningRig(const RigConfig& gearbox, const PipelineOptions& options,
                                            const RuntimeSettings& settings) {
  options.validate();
  settings.validate();
  auto rig = std::make_shared<RigConfig>(gearbox);
  rig->dynamics.mesh_damping_ratio = settings.mesh_damping_ratio;
  rig->dynamics.bearing_damping_ratio = settings.bearing_damping_ratio;
  if (options.dynamics && rig->dynamics.present) {
    // One speed for both mesh phases: the stiffness estimate's and the dynamics' (their grid too).
    if (!(options.pinion_speed_rpm > 0.0)) {
      throw InvalidInput("pinion_speed_rpm = " + formatValue(options.pinion_speed_rpm) + ": must be > 0 with dynamics");
    }
    rig->dynamics.speed_rpm = options.pinion_speed_rpm;
  }
  return rig;
}
}  // namespace

RigPipeline::RigPipeline(const RigConfig& rig, const PipelineOptions& options, const RuntimeSettings& settings)
    : rig_(runningRig(rig, options, settings)), options_(options), settings_(settings) {
  estimator_ = std::make_unique<StiffnessEstimator>(rig_, options_.limits);
  // One mesh table for the rig: the stiffness estimator's, shared read only with the dynamics and
  // the calibration.
  calibration_ = std::make_unique<CalibrationStage>(rig_, *estimator_, options_.calibrate, counters_);
  resonance_ = std::make_unique<ResonanceTracker>(*rig_, *estimator_, *calibration_, options_.resonance_threshold, counters_);
  const auto& teeth = estimator_->mesh().geometry().spec().teeth;
  phase_ = std::make_unique<PhaseSource>(options_, teeth[0], teeth[1], counters_);
  if (options_.dynamics) {
    // The sample consumers, in the order each sample reaches them.
    dynamics_ = std::make_unique<DynamicsStage>(rig_, *estimator_, options_, settings_.fidelity, *phase_, counters_);
    te_output_ = std::make_unique<TeOutput>(*phase_, resonance_->last(), counters_);
    te_spectrum_ = std::make_unique<TeSpectrumStage>(options_.spectrum_window, options_.spectrum_hop,
                                                     dynamics_->model().outputInterval(), counters_);
    mesh_periods_ = std::make_unique<MeshPeriodStage>(dynamics_->model(), estimator_->mesh().geometry().baseRadius(0),
                                                      counters_);
    dynamics_->addConsumer(*te_output_);
    dynamics_->addConsumer(*te_spectrum_);
    dynamics_->addConsumer(*mesh_periods_);
  }
}

void RigPipeline::reset(const std::string& reason) {
  estimator_->reset();
  if (dynamics_) dynamics_->reset();
  last_torque_.reset();
  last_preload_.reset();
  last_motion_.reset();
  last_stiffness_out_.reset();
  phase_->reset();
  calibration_->interrupt();
  resonance_->forget();  // the next accepted input republishes the resonance
  counters_.last_event = "reset: " + reason;
}

bool RigPipeline::observeClock(Stamp now, PipelineSink& /*sink*/) {
  // A looping bag's first messages can arrive before its /clock jump (separate connections, and
  // /clock lags by up to its period): if the stamps already restarted (rule 2) since the last jump,
  // that jump is the same restart; it is not reset a second time.
  bool back = last_clock_ && secondsBetween(*last_clock_, now) > options_.clock_jump_back;
  if (back && stamps_restarted_) {
    stamps_restarted_ = false;
    back = false;
  }
  if (back) {
    ++counters_.clock_resets;
    reset("clock went back from " + formatValue(last_clock_->toSec()) + " s to " + formatValue(now.toSec()) + " s");
  }
  last_clock_ = now;
  return back;
}

InputOutcome RigPipeline::reject(InputOutcome why, InputStream stream, Stamp stamp, const std::string& reason,
                                 std::uint64_t& rejected, std::string_view found) {
  ++rejected;
  refusals_.record(stream, why, stamp, reason, found);
  switch (why) {
    case InputOutcome::kZeroStamp: ++counters_.zero_stamps; break;
    case InputOutcome::kOutOfOrder: ++counters_.out_of_order; break;
    case InputOutcome::kInvalidValue: ++counters_.invalid_values; break;
    case InputOutcome::kUnreachableLoad: ++counters_.unreachable_loads; break;
    case InputOutcome::kWrongFrame: ++counters_.wrong_frames; break;
    case InputOutcome::kStampRange: ++counters_.stamps_out_of_range; break;
    case InputOutcome::kAccepted: break;
  }
  counters_.last_event = std::string(toString(stream)) + " rejected (" + toString(why) + "): " + reason;
  return why;
}

InputOutcome RigPipeline::checkStamp(Stamp stamp, std::optional<Stamp>& last, InputStream stream,
                                     PipelineSink& /*sink*/) {
  if (stamp.isZero()) return InputOutcome::kZeroStamp;
  if (!stamp.inRosRange()) return InputOutcome::kStampRange;  // rule 7
  if (last && stamp < *last) {
    const double back = secondsBetween(*last, stamp);
    if (back <= options_.stamp_jump_back) return InputOutcome::kOutOfOrder;
    ++counters_.stamp_resets;
    stamps_restarted_ = true;
    reset(std::string(toString(stream)) + " stamp went back by " + formatValue(back) + " s (more than ~stamp_jump_back): source restarted");
  }
  return InputOutcome::kAccepted;
}

double RigPipeline::pinionAngle(Stamp stamp) const { return phase_->pinionAngle(stamp); }

double RigPipeline::encoderPinionAngle(Stamp stamp) const { return phase_->encoderPinionAngle(stamp); }

std::optional<double> RigPipeline::encoderSilence(Stamp now) const { return phase_->encoderSilence(now); }

const char* RigPipeline::phaseSource() const { return phase_->name(); }

template <typename Validate, typename Update>
InputOutcome RigPipeline::apply(InputStream stream, Stamp stamp, std::optional<Stamp>& last, std::uint64_t& accepted,
                                std::uint64_t& rejected, PipelineSink& sink, Validate validate, Update update) {
  // Values first: a bad value must not trigger a stamp-rule reset before it is refused.
  try {
    validate();
  } catch (const InvalidInput& e) {
    return reject(InputOutcome::kInvalidValue, stream, stamp, e.what(), rejected);
  }
  const InputOutcome time_ok = checkStamp(stamp, last, stream, sink);
  if (time_ok != InputOutcome::kAccepted) {
    return reject(time_ok, stream, stamp, "stamp " + formatValue(stamp.toSec()) + " s", rejected);
  }
  const StiffnessEstimate* estimate = nullptr;
  try {
    // Transactional: throws without changing the state. No estimate: a shed input (no stiffness update).
    estimate = update();
  } catch (const InvalidInput& e) {
    return reject(InputOutcome::kInvalidValue, stream, stamp, e.what(), rejected);
  } catch (const UnreachableLoad& e) {
    return reject(InputOutcome::kUnreachableLoad, stream, stamp, e.what(), rejected);
  }
  // Taken: whatever becomes of its outputs (each guarded and counted on its own) the input is
  // counted accepted once and never also rejected.
  ++accepted;
  last = stamp;
  if (estimate) afterUpdate(stamp, *estimate, sink);
  return InputOutcome::kAccepted;
}

InputOutcome RigPipeline::torque(Stamp stamp, double torque, PipelineSink& sink, const InputOrigin& origin,
                                 Backlog backlog) {
  counters_.dropped_torque += torque_seq_.observe(origin.publisher, origin.seq);
  if (!options_.torque_frame.empty()) {
    // tf2 strips a leading '/' (ROS 1 frame ids may still carry one).
    const std::string_view frame = !origin.frame_id.empty() && origin.frame_id.front() == '/' ? origin.frame_id.substr(1)
                                                                                               : origin.frame_id;
    if (frame != options_.torque_frame) {
      return reject(InputOutcome::kWrongFrame, InputStream::kTorque, stamp,
                    "header.frame_id = '" + printableText(origin.frame_id) + "', expected ~torque_frame = '" +
                        options_.torque_frame + "' (the sign of torque.z selects the loaded flank)",
                    counters_.rejected_torque, origin.frame_id);
    }
  }
  const InputOutcome outcome = apply(
      InputStream::kTorque, stamp, last_torque_, counters_.accepted_torque, counters_.rejected_torque, sink,
      [&] { estimator_->validateTorque(torque); },
      [&]() -> const StiffnessEstimate* {
        // The mesh phase counts from the first torque input after a (re)start, as the dynamics do;
        // the origin is kept only if the input is accepted.
        checkMotionTimeout(stamp, sink);
        const Stamp origin_stamp = phase_->origin().value_or(stamp);
        if (backlog == Backlog::kShed) {
          // Shed: the rules and the dynamics, no stiffness update or message (its estimate would be
          // replaced by the newest input's before anyone could read it).
          phase_->setOrigin(origin_stamp);
          ++counters_.stiffness_shed;
          return nullptr;
        }
        const double angle = phase_->stiffnessAngle(stamp, origin_stamp);
        const StiffnessEstimate& e = estimator_->setTorque(torque, angle);
        phase_->setOrigin(origin_stamp);
        return &e;
      });
  if (outcome == InputOutcome::kAccepted) {
    // What the calibration (rule 11) pairs with the next readings (kept when the torque restarted the dynamics).
    if (!dynamics_ || dynamics_->takeTorque(stamp, torque, sink)) held_torque_ = torque;
  }
  return outcome;
}

InputOutcome RigPipeline::preload(Stamp stamp, const std::vector<PreloadSetting>& settings, PipelineSink& sink,
                                  const InputOrigin& origin) {
  counters_.dropped_preload += preload_seq_.observe(origin.publisher, origin.seq);
  return apply(InputStream::kPreload, stamp, last_preload_, counters_.accepted_preload, counters_.rejected_preload, sink,
               [&] { estimator_->validatePreloads(settings); },
               [&]() -> const StiffnessEstimate* { return &estimator_->setPreloads(settings); });
}

InputOutcome RigPipeline::motion(Stamp stamp, const MotionInput& reading, PipelineSink& sink, const InputOrigin& origin) {
  counters_.dropped_motion += motion_seq_.observe(origin.publisher, origin.seq);
  return apply(
      InputStream::kJointStates, stamp, last_motion_, counters_.accepted_motion, counters_.rejected_motion, sink,
      [&] {
        requireFinite("joint_states: pinion position", reading.pinion_angle);
        if (reading.pinion_velocity) {
          requireFinite("joint_states: pinion velocity", *reading.pinion_velocity);
          // The same bound as ~pinion_speed_rpm: +-1e5 rpm.
          if (std::abs(*reading.pinion_velocity) > 1e5 * kTwoPi / 60.0) {
            throwInvalid("joint_states: pinion velocity", *reading.pinion_velocity, "beyond +-1e5 rpm (10472 rad/s)");
          }
        }
        if (reading.gear_angle) requireFinite("joint_states: gear position", *reading.gear_angle);
      },
      [&]() -> const StiffnessEstimate* {
        acceptMotion(stamp, reading, sink);
        return nullptr;  // no stiffness message: the estimate has not changed
      });
}

InputOutcome RigPipeline::motionRefused(Stamp stamp, const std::string& reason, const InputOrigin& origin,
                                        std::string_view found) {
  counters_.dropped_motion += motion_seq_.observe(origin.publisher, origin.seq);
  return reject(InputOutcome::kInvalidValue, InputStream::kJointStates, stamp, reason, counters_.rejected_motion, found);
}

void RigPipeline::acceptMotion(Stamp stamp, const MotionInput& m, PipelineSink& sink) {
  // Transactional: the reading is checked against the last one before anything changes.
  bool continuous = false;
  PhaseSource::Reading accepted = phase_->unwrap(stamp, m, continuous);
  checkMotionTimeout(stamp, sink);
  phase_->checkGearRatio(accepted);
  // Rule 10: the dynamics run up to this reading with the motion before it (after a gap, rule 4:
  // they stop, and the next torque input restarts them at the measured phase).
  if (dynamics_) {
    dynamics_->stopAfterGap(stamp);
    dynamics_->advanceTo(stamp, sink);
  }
  // The first reading moves the mesh phase from the nominal count to the measured one (a jump):
  // the running block of mesh periods would count a period that never was.
  if (!phase_->encodersDrive() && mesh_periods_) mesh_periods_->restart();
  if (calibration_->calibrator() && accepted.gear) {
    calibration_->reading(stamp, accepted.pinion, *accepted.gear, phase_->meshPhase(accepted.pinion), accepted.speed,
                          held_torque_, continuous, sink);
  }
  phase_->anchorTo(accepted);
  if (dynamics_) dynamics_->followAnchor(stamp);
}

void RigPipeline::checkMotionTimeout(Stamp stamp, PipelineSink& sink) {
  const std::optional<Stamp> at = phase_->encodersTimedOut(stamp);
  if (!at) return;
  if (dynamics_) dynamics_->advanceTo(*at, sink);
  phase_->fallBackToNominal(*at);
  if (dynamics_) dynamics_->followAnchor(*at);
}

void RigPipeline::afterUpdate(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink) {
  // Coalescing by stamp, not by wall time, so a replay coalesces exactly as the live node did.
  const bool due = settings_.stiffness_rate <= 0.0 || !last_stiffness_out_ || stamp < *last_stiffness_out_ ||
                   secondsBetween(stamp, *last_stiffness_out_) >= 1.0 / settings_.stiffness_rate;
  if (due) {
    try {
      sink.stiffness(stamp, estimate, calibration_->stiffnessBands(estimate));
      last_stiffness_out_ = stamp;
      ++counters_.stiffness_out;
    } catch (const Error& e) {
      // The sink refused the message (a field it will not publish, such as a non-finite one): the
      // input stays taken, the dynamics still get its stiffness below, the refusal is counted.
      ++counters_.stiffness_refused;
      counters_.last_event = std::string("stiffness message not published: ") + e.what();
    }
  } else {
    ++counters_.stiffness_coalesced;
  }
  pushStiffness(stamp, estimate, sink);
}

void RigPipeline::pushStiffness(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink) {
  if (!dynamics_) return;
  // Every accepted input hands the new bearing stiffness to the dynamics at its own stamp (rule
  // 10; after a gap, rule 4, they stop first), then the resonance estimate is refreshed.
  dynamics_->takeBearingStiffness(stamp, sink);
  const DampingRatios damping{settings_.mesh_damping_ratio, settings_.bearing_damping_ratio};
  resonance_->update(stamp, estimate, damping, dynamics_->model(), sink);
}

void RigPipeline::apply(const RuntimeSettings& settings) {
  settings.validate();  // all or nothing: nothing below throws for valid settings
  const bool damping_changed = settings.mesh_damping_ratio != settings_.mesh_damping_ratio ||
                               settings.bearing_damping_ratio != settings_.bearing_damping_ratio;
  settings_ = settings;
  if (damping_changed) {
    if (dynamics_) dynamics_->model().setDamping(settings.mesh_damping_ratio, settings.bearing_damping_ratio);
    resonance_->forget();  // damped frequencies and ratios changed: republish at the next input
  }
  if (dynamics_) {
    // The mesh-force estimator depends on the fidelity (MeshPeriodStatistics): a block spans one.
    if (dynamics_->model().fidelity() != settings.fidelity) mesh_periods_->restart();
    dynamics_->model().setFidelity(settings.fidelity);
  }
}

}  // namespace drivetrain_stiffness

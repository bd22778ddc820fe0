#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

namespace {
/// The rig as the pipeline runs it, built once and shared read only by the stiffness estimator, the
/// dynamics and the calibration: the gearbox with the start-up damping ratios of the run-time
/// settings and, with dynamics, the nominal speed of the options.
std::shared_ptr<const RigConfig> runningRig(const RigConfig& gearbox,
                                            const PipelineOptions& options,
                                            const RuntimeSettings& settings) {
  options.validate();
  settings.validate();
  auto rig = std::make_shared<RigConfig>(gearbox);
  rig->dynamics.mesh_damping_ratio = settings.mesh_damping_ratio;
  rig->dynamics.bearing_damping_ratio = settings.bearing_damping_ratio;
  if (options.dynamics && rig->dynamics.present) {
    // One speed for both mesh phases: the stiffness estimate's and the dynamics' (their grid too).
    if (!(options.pinion_speed_rpm > 0.0)) {
      throw InvalidInput("pinion_speed_rpm = " + formatValue(options.pinion_speed_rpm) +
                         ": must be > 0 with dynamics");
    }
    rig->dynamics.speed_rpm = options.pinion_speed_rpm;
  }
  return rig;
}
}  // namespace

RigPipeline::RigPipeline(const RigConfig& rig, const PipelineOptions& options)
    : RigPipeline(rig, options, RuntimeSettings::forRig(rig)) {}

RigPipeline::RigPipeline(const RigConfig& rig, const PipelineOptions& options,
                         const RuntimeSettings& settings)
    : rig_(runningRig(rig, options, settings)), options_(options), settings_(settings) {
  gate_ = std::make_unique<InputGate>(options_, counters_);
  // One mesh table for the rig: the stiffness estimator's, shared read only with the dynamics and
  // the calibration.
  estimator_ = std::make_unique<StiffnessEstimator>(rig_, options_.limits);
  calibration_ =
      std::make_unique<CalibrationStage>(rig_, *estimator_, options_.calibrate, counters_);
  resonance_ = std::make_unique<ResonanceTracker>(*rig_, *estimator_, *calibration_,
                                                  options_.resonance_threshold, counters_);
  const auto& teeth = estimator_->mesh().geometry().spec().teeth;
  vibration_ =
      std::make_unique<VibrationInput>(vibrationChannels(*rig_, options_.vibration_channels),
                                       options_.vibration_record, counters_.vibration);
  phase_ = std::make_unique<PhaseSource>(options_, teeth[0], teeth[1], counters_);
  modal_ = std::make_unique<ModalStage>(*rig_, *vibration_, *phase_, *estimator_, *calibration_,
                                        options_, counters_);
  if (options_.dynamics) {
    dynamics_ = std::make_unique<DynamicsStage>(rig_, *estimator_, options_, settings_.fidelity,
                                                *phase_, counters_);
    te_output_ = std::make_unique<TeOutput>(*phase_, resonance_->last(), counters_);
    te_spectrum_ =
        std::make_unique<TeSpectrumStage>(options_.spectrum_window, options_.spectrum_hop,
                                          dynamics_->model().outputInterval(), counters_);
    mesh_periods_ = std::make_unique<MeshPeriodStage>(
        dynamics_->model(), estimator_->mesh().geometry().baseRadius(0), counters_);
    // The order in which each sample reaches them (and so the sink's calls).
    dynamics_->addConsumer(*te_output_);
    dynamics_->addConsumer(*te_spectrum_);
    dynamics_->addConsumer(*mesh_periods_);
  }
}

void RigPipeline::reset(const std::string& reason) {
  estimator_->reset();
  if (dynamics_) dynamics_->reset();
  gate_->forgetStamps();
  last_stiffness_out_.reset();
  phase_->reset();
  calibration_->interrupt();
  resonance_->forget();  // the next accepted input republishes the resonance
  vibration_->reset();
  modal_->reset();
  counters_.last_event = "reset: " + reason;
}

bool RigPipeline::observeClock(Stamp now, PipelineSink& /*sink*/) {
  const std::optional<std::string> jumped = gate_->observeClock(now);  // the clock-jump rule
  if (jumped) reset(*jumped);
  return jumped.has_value();
}

double RigPipeline::pinionAngle(Stamp stamp) const { return phase_->pinionAngle(stamp); }

double RigPipeline::encoderPinionAngle(Stamp stamp) const {
  return phase_->encoderPinionAngle(stamp);
}

std::optional<double> RigPipeline::encoderSilence(Stamp now) const {
  return phase_->encoderSilence(now);
}

const char* RigPipeline::phaseSource() const { return phase_->name(); }

template <typename Validate, typename Update>
InputOutcome RigPipeline::take(InputStream stream, Stamp stamp, PipelineSink& sink,
                               Validate validate, Update update) {
  // Values first: a bad value must not trigger a source-restart reset before it is refused.
  try {
    validate();
  } catch (const InvalidInput& e) {
    return gate_->reject(InputOutcome::kInvalidValue, stream, stamp, e.what());
  }
  const InputOutcome time_ok = gate_->checkStamp(stream, stamp);
  if (time_ok != InputOutcome::kAccepted) {
    return gate_->reject(time_ok, stream, stamp, "stamp " + formatValue(stamp.toSec()) + " s");
  }
  if (const std::optional<std::string> restarted = gate_->noteSourceRestart(stream, stamp))
    reset(*restarted);
  const StiffnessEstimate* estimate = nullptr;
  try {
    // Transactional: throws without changing the state. No estimate: a shed input (no stiffness
    // update).
    estimate = update();
  } catch (const InvalidInput& e) {
    return gate_->reject(InputOutcome::kInvalidValue, stream, stamp, e.what());
  } catch (const UnreachableLoad& e) {
    return gate_->reject(InputOutcome::kUnreachableLoad, stream, stamp, e.what());
  }
  // Taken: whatever becomes of its outputs (each guarded and counted on its own) the input is
  // counted accepted once and never also rejected.
  gate_->accept(stream, stamp);
  if (estimate) afterUpdate(stamp, *estimate, sink);
  return InputOutcome::kAccepted;
}

InputOutcome RigPipeline::torque(Stamp stamp, double torque, PipelineSink& sink,
                                 const InputOrigin& origin, Backlog backlog) {
  gate_->countDrops(InputStream::kTorque, origin);
  if (gate_->checkFrame(stamp, origin) != InputOutcome::kAccepted) return InputOutcome::kWrongFrame;
  const InputOutcome outcome = take(
      InputStream::kTorque, stamp, sink, [&] { estimator_->validateTorque(torque); },
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
        const StiffnessEstimate& e =
            estimator_->setTorque(torque, phase_->stiffnessAngle(stamp, origin_stamp));
        phase_->setOrigin(origin_stamp);
        return &e;
      });
  // The torque the calibration pairs the next readings with (kept as it was when this one restarted
  // the dynamics: what the pipeline has always done).
  if (outcome == InputOutcome::kAccepted &&
      (!dynamics_ || dynamics_->takeTorque(stamp, torque, sink))) {
    held_torque_ = torque;
  }
  return outcome;
}

InputOutcome RigPipeline::preload(Stamp stamp, const std::vector<PreloadSetting>& settings,
                                  PipelineSink& sink, const InputOrigin& origin) {
  gate_->countDrops(InputStream::kPreload, origin);
  return take(
      InputStream::kPreload, stamp, sink, [&] { estimator_->validatePreloads(settings); },
      [&]() -> const StiffnessEstimate* { return &estimator_->setPreloads(settings); });
}

InputOutcome RigPipeline::motion(Stamp stamp, const MotionInput& reading, PipelineSink& sink,
                                 const InputOrigin& origin) {
  gate_->countDrops(InputStream::kJointStates, origin);
  return take(
      InputStream::kJointStates, stamp, sink, [&] { InputGate::validateReading(reading); },
      [&]() -> const StiffnessEstimate* {
        acceptMotion(stamp, reading, sink);
        return nullptr;  // no stiffness message: the estimate has not changed
      });
}

InputOutcome RigPipeline::motionRefused(Stamp stamp, const std::string& reason,
                                        const InputOrigin& origin, std::string_view found) {
  gate_->countDrops(InputStream::kJointStates, origin);
  return gate_->reject(InputOutcome::kInvalidValue, InputStream::kJointStates, stamp, reason,
                       found);
}

InputOutcome RigPipeline::vibration(Stamp stamp, const VibrationBlockView& block,
                                    PipelineSink& sink, const InputOrigin& origin) {
  gate_->countDrops(InputStream::kVibration, origin);
  const InputOutcome outcome = take(
      InputStream::kVibration, stamp, sink, [&] { vibration_->validate(block); },
      [&]() -> const StiffnessEstimate* {
        vibration_->append(stamp, block, origin.seq);
        return nullptr;  // no stiffness message: the estimate has not changed
      });
  if (outcome != InputOutcome::kAccepted) {
    vibration_->interrupt();
    return outcome;
  }
  modal_->afterBlock(stamp, block.size / block.channel_count, held_torque_, sink);
  return outcome;
}

void RigPipeline::finish(PipelineSink& sink) { modal_->finish(sink); }

void RigPipeline::acceptMotion(Stamp stamp, const MotionInput& m, PipelineSink& sink) {
  // Transactional: the reading is checked against the last one before anything changes.
  bool continuous = false;
  PhaseSource::Reading accepted = phase_->unwrap(stamp, m, continuous);
  checkMotionTimeout(stamp, sink);
  phase_->checkGearRatio(accepted);
  // The own-stamp rule: the dynamics run up to this reading with the motion before it (the gap
  // rule: they stop, and the next torque input restarts them at the measured phase).
  if (dynamics_) {
    dynamics_->stopAfterGap(stamp);
    dynamics_->advanceTo(stamp, sink);
  }
  // The first reading moves the mesh phase from the nominal count to the measured one (a jump):
  // the running block of mesh periods would count a period that never was.
  if (!phase_->encodersDrive() && mesh_periods_) mesh_periods_->restart();
  if (calibration_->calibrator() && accepted.gear) {  // the calibration rule
    calibration_->reading(stamp, accepted.pinion, *accepted.gear,
                          phase_->meshPhase(accepted.pinion), accepted.speed, held_torque_,
                          continuous, sink);
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
  const bool due = settings_.stiffness_rate <= 0.0 || !last_stiffness_out_ ||
                   stamp < *last_stiffness_out_ ||
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

void RigPipeline::pushStiffness(Stamp stamp, const StiffnessEstimate& estimate,
                                PipelineSink& sink) {
  if (!dynamics_) return;
  // Every accepted input hands the new bearing stiffness to the dynamics at its own stamp (after a
  // gap they stop first), then the resonance estimate is refreshed.
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
    if (dynamics_)
      dynamics_->model().setDamping(settings.mesh_damping_ratio, settings.bearing_damping_ratio);
    resonance_->forget();  // damped frequencies and ratios changed: republish at the next input
  }
  if (dynamics_) {
    // The mesh-force estimator depends on the fidelity (MeshPeriodStatistics): a block spans one.
    if (dynamics_->model().fidelity() != settings.fidelity) mesh_periods_->restart();
    dynamics_->model().setFidelity(settings.fidelity);
  }
}

}  // namespace drivetrain_stiffness

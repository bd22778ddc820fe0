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
  gate_ = std::make_unique<InputGate>(options_);
  // One mesh table for the rig: the stiffness estimator's, shared read only with the dynamics and
  // the calibration.
  estimator_ = std::make_unique<StiffnessEstimator>(rig_, options_.limits);
  calibration_ = std::make_unique<CalibrationStage>(rig_, *estimator_, options_.calibrate);
  resonance_ = std::make_unique<ResonanceTracker>(*rig_, *estimator_, *calibration_,
                                                  options_.resonance_threshold);
  const auto& teeth = estimator_->mesh().geometry().spec().teeth;
  vibration_ = std::make_unique<VibrationInput>(
      vibrationChannels(*rig_, options_.vibration_channels), options_.vibration_record);
  phase_ = std::make_unique<PhaseSource>(options_, teeth[0], teeth[1]);
  modal_ = std::make_unique<ModalStage>(*rig_, *vibration_, *phase_, *estimator_, *calibration_,
                                        options_);
  if (options_.dynamics) {
    dynamics_ = std::make_unique<DynamicsStage>(rig_, *estimator_, options_, settings_.fidelity);
    te_output_ = std::make_unique<TeOutput>(*phase_, resonance_->last());
    te_spectrum_ = std::make_unique<TeSpectrumStage>(
        options_.spectrum_window, options_.spectrum_hop, dynamics_->dynamics().outputInterval());
    mesh_periods_ = std::make_unique<MeshPeriodStage>(dynamics_->dynamics(),
                                                      estimator_->mesh().geometry().baseRadius(0));
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
  events_.record("reset: " + reason);
}

bool RigPipeline::observeClock(Stamp now, PipelineSink& /*sink*/) {
  const std::optional<std::string> jumped = gate_->observeClock(now);  // the clock-jump rule
  if (jumped) reset(*jumped);
  return jumped.has_value();
}

const PipelineCounters& RigPipeline::counters() const {
  PipelineCounters& m = merged_;
  static_cast<GateCounters&>(m) = gate_->counters();
  static_cast<PhaseCounters&>(m) = phase_->counters();
  static_cast<DynamicsCounters&>(m) = dynamics_ ? dynamics_->counters() : DynamicsCounters{};
  static_cast<ResonanceCounters&>(m) = resonance_->counters();
  static_cast<StiffnessOutputCounters&>(m) = counters_;
  static_cast<TeOutputCounters&>(m) = te_output_ ? te_output_->counters() : TeOutputCounters{};
  static_cast<SpectrumCounters&>(m) = te_spectrum_ ? te_spectrum_->counters() : SpectrumCounters{};
  static_cast<MeshPeriodCounters&>(m) =
      mesh_periods_ ? mesh_periods_->counters() : MeshPeriodCounters{};
  static_cast<CalibrationCounters&>(m) = calibration_->counters();
  static_cast<ModalCounters&>(m) = modal_->counters();
  m.vibration = vibration_->counters();
  m.dynamics_errors = m.model_errors + m.resonance_errors;
  // The last event is the latest of any stage's (null: a stage that is not running).
  const EventLog* last = &events_;
  for (const EventLog* e :
       {&gate_->events(), &phase_->events(), &resonance_->events(), &calibration_->events(),
        &modal_->events(), dynamics_ ? &dynamics_->events() : nullptr,
        mesh_periods_ ? &mesh_periods_->events() : nullptr}) {
    if (e && e->order() > last->order()) last = e;
  }
  m.last_event = last->last();
  return m;
}

PipelineDiagnostics RigPipeline::diagnostics(Stamp now) const {
  std::optional<DynamicsDiagnostics> dynamics;
  if (dynamics_) {
    const DynamicsEstimator& d = dynamics_->dynamics();
    dynamics = DynamicsDiagnostics{d.fidelity(), d.outputInterval(), d.work()};
  }
  return PipelineDiagnostics{counters(),
                             gate_->refusals(),
                             phase_->name(),
                             phase_->encoderSilence(now),
                             vibration_->unknownNames(),
                             gate_->unnumberedPublishers(),
                             dynamics};
}

double RigPipeline::pinionAngle(Stamp stamp) const { return phase_->pinionAngle(stamp); }

double RigPipeline::encoderPinionAngle(Stamp stamp) const {
  return phase_->encoderPinionAngle(stamp);
}

std::optional<double> RigPipeline::encoderSilence(Stamp now) const {
  return phase_->encoderSilence(now);
}

const char* RigPipeline::phaseSource() const { return phase_->name(); }

template <typename Validate>
InputOutcome RigPipeline::gate(InputStream stream, Stamp stamp, Validate validate) {
  // Values first: a bad value must not trigger a source-restart reset before it is refused.
  const InputOutcome value_ok = refuseOnError(stream, stamp, validate);
  if (value_ok != InputOutcome::kAccepted) return value_ok;
  const InputOutcome time_ok = gate_->checkStamp(stream, stamp);
  if (time_ok != InputOutcome::kAccepted) {
    return gate_->reject(time_ok, stream, stamp, "stamp " + formatValue(stamp.toSec()) + " s");
  }
  if (const std::optional<std::string> restarted = gate_->noteSourceRestart(stream, stamp))
    reset(*restarted);
  return InputOutcome::kAccepted;
}

template <typename F>
InputOutcome RigPipeline::refuseOnError(InputStream stream, Stamp stamp, F f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return gate_->reject(InputOutcome::kInvalidValue, stream, stamp, e.what());
  } catch (const UnreachableLoad& e) {
    return gate_->reject(InputOutcome::kUnreachableLoad, stream, stamp, e.what());
  }
  return InputOutcome::kAccepted;
}

Advance RigPipeline::advance(Stamp stamp, PipelineSink& sink) {
  // The encoders' time-out at its own moment: the dynamics run up to it on the encoders' phase,
  // which from there runs at the nominal speed.
  if (const std::optional<Stamp> at = phase_->encodersTimedOut(stamp)) {
    if (dynamics_) dynamics_->advanceTo(*at, sink);
    phase_->fallBackToNominal(*at);
    followPhase(*at);
  }
  if (!dynamics_) return Advance::kStopped;
  // The own-stamp rule, after the gap rule: a paused rig restarts the model at the next torque
  // input instead of integrating the gap.
  dynamics_->stopAfterGap(stamp);
  return dynamics_->advanceTo(stamp, sink);
}

InputOutcome RigPipeline::torque(Stamp stamp, double torque, PipelineSink& sink,
                                 const InputOrigin& origin, Backlog backlog) {
  constexpr InputStream kStream = InputStream::kTorque;
  gate_->countDrops(kStream, origin);
  if (gate_->checkFrame(stamp, origin) != InputOutcome::kAccepted) return InputOutcome::kWrongFrame;
  InputOutcome outcome = gate(kStream, stamp, [&] { estimator_->validateTorque(torque); });
  if (outcome != InputOutcome::kAccepted) return outcome;
  const Advance advanced = advance(stamp, sink);
  const StiffnessEstimate* estimate = nullptr;
  outcome = refuseOnError(kStream, stamp,
                          [&] { estimate = applyTorque(stamp, torque, backlog, advanced); });
  if (outcome != InputOutcome::kAccepted) return outcome;
  gate_->accept(kStream, stamp);
  if (estimate) publishStiffness(stamp, *estimate, sink);
  return InputOutcome::kAccepted;
}

const StiffnessEstimate* RigPipeline::applyTorque(Stamp stamp, double torque, Backlog backlog,
                                                  Advance advanced) {
  // The nominal mesh phase counts from the first torque input after a (re)start of the pipeline;
  // the stiffness of the input that sets it is taken at that origin.
  const Stamp origin = phase_->origin().value_or(stamp);
  const StiffnessEstimate* estimate = nullptr;
  if (backlog == Backlog::kShed) {
    // Shed: the rules and the dynamics, no stiffness update or message (its estimate would be
    // replaced by the newest input's before anyone could read it).
    ++counters_.stiffness_shed;
  } else {
    // Transactional: throws with nothing changed.
    estimate = &estimator_->setTorque(torque, phase_->stiffnessAngle(stamp, origin));
  }
  phase_->setOrigin(origin);
  held_torque_ = torque;
  if (!dynamics_) return estimate;
  if (estimate) dynamics_->takeBearingStiffness(stamp, advanced);
  if (dynamics_->takeTorque(stamp, torque) == TorqueTaken::kRestarted) {
    // The nominal phase restarts with the dynamics; measured motion: they start at its phase.
    phase_->setOrigin(stamp);
    followPhase(stamp);
  }
  return estimate;
}

InputOutcome RigPipeline::preload(Stamp stamp, const std::vector<PreloadSetting>& settings,
                                  PipelineSink& sink, const InputOrigin& origin) {
  constexpr InputStream kStream = InputStream::kPreload;
  gate_->countDrops(kStream, origin);
  InputOutcome outcome = gate(kStream, stamp, [&] { estimator_->validatePreloads(settings); });
  if (outcome != InputOutcome::kAccepted) return outcome;
  const Advance advanced = advance(stamp, sink);
  const StiffnessEstimate* estimate = nullptr;
  outcome = refuseOnError(kStream, stamp, [&] { estimate = &estimator_->setPreloads(settings); });
  if (outcome != InputOutcome::kAccepted) return outcome;
  if (dynamics_) dynamics_->takeBearingStiffness(stamp, advanced);
  gate_->accept(kStream, stamp);
  publishStiffness(stamp, *estimate, sink);
  return InputOutcome::kAccepted;
}

InputOutcome RigPipeline::motion(Stamp stamp, const MotionInput& reading, PipelineSink& sink,
                                 const InputOrigin& origin) {
  constexpr InputStream kStream = InputStream::kJointStates;
  gate_->countDrops(kStream, origin);
  InputOutcome outcome = gate(kStream, stamp, [&] { InputGate::validateReading(reading); });
  if (outcome != InputOutcome::kAccepted) return outcome;
  // Unwrapped against the last reading before anything moves (the encoders rule's speed bound).
  PhaseSource::Reading unwrapped;
  bool continuous = false;
  outcome = refuseOnError(kStream, stamp,
                          [&] { unwrapped = phase_->unwrap(stamp, reading, continuous); });
  if (outcome != InputOutcome::kAccepted) return outcome;
  advance(stamp, sink);
  applyMotion(stamp, unwrapped);
  gate_->accept(kStream, stamp);
  if (calibration_->calibrator() && unwrapped.gear) {  // the calibration rule
    calibration_->reading(stamp, unwrapped.pinion, *unwrapped.gear,
                          phase_->meshPhase(unwrapped.pinion), unwrapped.speed, held_torque_,
                          continuous, sink);
  }
  return InputOutcome::kAccepted;
}

void RigPipeline::applyMotion(Stamp stamp, PhaseSource::Reading& reading) {
  phase_->checkGearRatio(reading);
  // The first reading moves the mesh phase from the nominal count to the measured one (a jump):
  // the running block of mesh periods would count a period that never was.
  if (!phase_->encodersDrive() && mesh_periods_) mesh_periods_->restart();
  phase_->anchorTo(reading);
  followPhase(stamp);
}

InputOutcome RigPipeline::motionRefused(Stamp stamp, const std::string& reason,
                                        const InputOrigin& origin, std::string_view found) {
  gate_->countDrops(InputStream::kJointStates, origin);
  return gate_->reject(InputOutcome::kInvalidValue, InputStream::kJointStates, stamp, reason,
                       found);
}

InputOutcome RigPipeline::vibration(Stamp stamp, const VibrationBlockView& block,
                                    PipelineSink& sink, const InputOrigin& origin) {
  // No advance: a block's stamp is its first sample's, and the record has a clock of its own.
  constexpr InputStream kStream = InputStream::kVibration;
  gate_->countDrops(kStream, origin);
  InputOutcome outcome = gate(kStream, stamp, [&] { vibration_->validate(block); });
  if (outcome == InputOutcome::kAccepted) {
    outcome = refuseOnError(kStream, stamp, [&] { vibration_->append(stamp, block, origin.seq); });
  }
  if (outcome != InputOutcome::kAccepted) {
    vibration_->interrupt();
    return outcome;
  }
  gate_->accept(kStream, stamp);
  modal_->afterBlock(stamp, block.size / block.channel_count, held_torque_, sink);
  return outcome;
}

void RigPipeline::finish(PipelineSink& sink) { modal_->finish(sink); }

void RigPipeline::followPhase(Stamp stamp) {
  if (!dynamics_ || !phase_->anchor()) return;
  const std::optional<DynamicsStage::Moment> at = dynamics_->momentAtOrAfter(stamp);
  if (!at) return;  // stopped: a restart follows the phase from its own stamp
  dynamics_->followMotion(*at, phase_->meshTurns(phase_->pinionAngle(at->stamp)),
                          phase_->meshTurns(phase_->anchor()->speed));
}

void RigPipeline::publishStiffness(Stamp stamp, const StiffnessEstimate& estimate,
                                   PipelineSink& sink) {
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
      // input stays taken, the refusal is counted.
      ++counters_.stiffness_refused;
      events_.record(std::string("stiffness message not published: ") + e.what());
    }
  } else {
    ++counters_.stiffness_coalesced;
  }
  if (!dynamics_) return;
  const DampingRatios damping{settings_.mesh_damping_ratio, settings_.bearing_damping_ratio};
  resonance_->update(stamp, estimate, damping, dynamics_->dynamics(), sink);
}

void RigPipeline::apply(const RuntimeSettings& settings) {
  settings.validate();  // all or nothing: nothing below throws for valid settings
  const bool damping_changed = settings.mesh_damping_ratio != settings_.mesh_damping_ratio ||
                               settings.bearing_damping_ratio != settings_.bearing_damping_ratio;
  settings_ = settings;
  if (damping_changed) {
    if (dynamics_)
      dynamics_->dynamics().setDamping(settings.mesh_damping_ratio, settings.bearing_damping_ratio);
    resonance_->forget();  // damped frequencies and ratios changed: republish at the next input
  }
  if (dynamics_) {
    // The mesh-force estimator depends on the fidelity (MeshPeriodStatistics): a block spans one.
    if (dynamics_->dynamics().fidelity() != settings.fidelity) mesh_periods_->restart();
    dynamics_->dynamics().setFidelity(settings.fidelity);
  }
}

}  // namespace drivetrain_stiffness

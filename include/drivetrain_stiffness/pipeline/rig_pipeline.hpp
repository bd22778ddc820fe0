// The online pipeline, free of ROS, run by the node, the nodelet and drivetrain_replay: inputs
// with their stamps and the caller's clock in, every output to a PipelineSink. It composes the
// stages of docs/pipeline.md and applies the rules of docs/ros_api.md, "Time and input rules", in
// one order per input: gate, advance (the phase and the dynamics to the input's stamp), apply,
// publish. It alone owns the phase source and decides when the dynamics advance. It reads no
// clock, so a replay with the recorded stamps is bit-identical to the live run. Only the library's
// own errors (core/errors.hpp) are caught, each counted by its stage with its reason; a
// programming error passes through.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/core/dynamics/motion.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"
#include "drivetrain_stiffness/pipeline/dynamics_stage.hpp"
#include "drivetrain_stiffness/pipeline/input_gate.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/mesh_period_stage.hpp"
#include "drivetrain_stiffness/pipeline/modal_stage.hpp"
#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"
#include "drivetrain_stiffness/pipeline/resonance_tracker.hpp"
#include "drivetrain_stiffness/pipeline/runtime_settings.hpp"
#include "drivetrain_stiffness/pipeline/te_output.hpp"
#include "drivetrain_stiffness/pipeline/te_spectrum_stage.hpp"
#include "drivetrain_stiffness/pipeline/vibration_input.hpp"

namespace drivetrain_stiffness {

/// The dynamics as /diagnostics and summary.json report them.
struct DynamicsDiagnostics {
  Fidelity fidelity = Fidelity::kFull;
  double output_interval = 0.0;  ///< [s]
  DynamicsWork work;
};

/// What /diagnostics, summary.json and the run summary read of a pipeline, as one value; its
/// references stay valid until the pipeline's next call.
struct PipelineDiagnostics {
  const PipelineCounters& counters;
  const RefusalTally& refusals;
  const char* phase_source;               ///< PhaseSource::name
  std::optional<double> encoder_silence;  ///< [s] since the last reading, at the caller's clock
  const std::vector<std::string>& unknown_vibration_channels;
  std::size_t unnumbered_publishers;            ///< whose drops cannot be seen
  std::optional<DynamicsDiagnostics> dynamics;  ///< none without ~dynamics
};

class RigPipeline {
 public:
  /// Throws InvalidInput naming the field for an invalid rig, option or setting. Without settings:
  /// RuntimeSettings::forRig.
  RigPipeline(const RigConfig& rig, const PipelineOptions& options,
              const RuntimeSettings& settings);
  RigPipeline(const RigConfig& rig, const PipelineOptions& options);

  /// The caller's clock (ROS time, or the bag's record time); true if the clock-jump rule reset
  /// all.
  bool observeClock(Stamp now, PipelineSink& sink);
  /// Pinion torque [N*m] (torque.z in ~torque_frame). kShed: the rules and the dynamics only.
  InputOutcome torque(Stamp stamp, double torque, PipelineSink& sink,
                      const InputOrigin& origin = {}, Backlog backlog = Backlog::kNone);
  /// New preloads of the named supports.
  InputOutcome preload(Stamp stamp, const std::vector<PreloadSetting>& settings, PipelineSink& sink,
                       const InputOrigin& origin = {});
  /// One encoder reading (the encoders rule).
  InputOutcome motion(Stamp stamp, const MotionInput& reading, PipelineSink& sink,
                      const InputOrigin& origin = {});
  /// A joint_states message the caller could not convert (no pinion joint): refused as an invalid
  /// value, `found` (its joint names) in the tally.
  InputOutcome motionRefused(Stamp stamp, const std::string& reason, const InputOrigin& origin = {},
                             std::string_view found = {});
  /// One accelerometer block at `stamp` (its first sample): the vibration block rules.
  InputOutcome vibration(Stamp stamp, const VibrationBlockView& block, PipelineSink& sink,
                         const InputOrigin& origin = {});
  /// The input ended (a replay's end of bag): an identification still pending is applied.
  void finish(PipelineSink& sink);
  /// The vibration record and its channel map.
  const VibrationInput& vibrationInput() const { return *vibration_; }
  /// What drives the mesh phase (PhaseSource::name).
  const char* phaseSource() const;
  /// [s] since the last reading while the encoders drive the phase (the time-out is taken on input
  /// stamps: with every input stopped /diagnostics shows this age instead).
  std::optional<double> encoderSilence(Stamp now) const;
  /// Publishers whose drops cannot be seen (header.seq constant).
  std::size_t unnumberedPublishers() const { return gate_->unnumberedPublishers(); }
  /// Back to the configured preloads, zero torque, dynamics restarted at the next torque input.
  void reset(const std::string& reason);

  /// New run-time settings, applied whole or refused (InvalidInput naming the field) with nothing
  /// changed; a damping change republishes the resonance at the next input.
  void apply(const RuntimeSettings& settings);
  const RuntimeSettings& settings() const { return settings_; }

  /// Every stage's counters merged under the keys of namedCounters, with the last event of any
  /// stage. Valid until the next call; no allocation unless the last event's text grew.
  const PipelineCounters& counters() const;
  /// Every figure /diagnostics and the replay's summary report, `now` the caller's clock.
  PipelineDiagnostics diagnostics(Stamp now) const;
  /// Every refused input by stream and reason.
  const RefusalTally& refusals() const { return gate_->refusals(); }
  const PipelineOptions& options() const { return options_; }
  const StiffnessEstimator& estimator() const { return *estimator_; }
  const DynamicsEstimator* dynamics() const { return dynamics_ ? &dynamics_->dynamics() : nullptr; }
  /// The live calibration, or null (no calibration block, or ~calibrate off).
  const Calibrator* calibrator() const { return calibration_->calibrator(); }
  /// The rig as run (shared read only): the gearbox with the nominal speed and start-up damping.
  const RigConfig& rig() const { return *rig_; }
  const std::optional<ResonanceEstimate>& lastResonance() const { return resonance_->last(); }
  /// [rad] PhaseSource::pinionAngle and ::encoderPinionAngle (what the tf frames draw).
  double pinionAngle(Stamp stamp) const;
  double encoderPinionAngle(Stamp stamp) const;

 private:
  /// The gate: the value rules (`validate` throws InvalidInput), the time rules and the source
  /// restart rule. kAccepted: the input goes on.
  template <typename Validate>
  InputOutcome gate(InputStream stream, Stamp stamp, Validate validate);
  /// The gate's refusal of an input whose value `f` throws for (InvalidInput, UnreachableLoad);
  /// kAccepted if it does not.
  template <typename F>
  InputOutcome refuseOnError(InputStream stream, Stamp stamp, F f);
  /// The phase (the encoders' time-out) and the dynamics (the gap rule, then the model) to
  /// `stamp`; the result for the bearing stiffness taken at it.
  Advance advance(Stamp stamp, PipelineSink& sink);
  /// The stiffness estimate at the torque (null: shed), the torque held for the dynamics and the
  /// calibration. Throws what StiffnessEstimator::setTorque throws, with nothing changed.
  const StiffnessEstimate* applyTorque(Stamp stamp, double torque, Backlog backlog,
                                       Advance advanced);
  /// The reading becomes the phase's anchor and the dynamics follow it.
  void applyMotion(Stamp stamp, PhaseSource::Reading& reading);
  /// The stiffness message (throttled by ~stiffness_rate on stamps), then the resonance.
  void publishStiffness(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink);
  /// The dynamics follow the phase source's anchor from `stamp` (or the model's time, if later).
  void followPhase(Stamp stamp);

  std::shared_ptr<const RigConfig> rig_;  ///< first: the stages share it
  PipelineOptions options_;
  RuntimeSettings settings_;
  StiffnessOutputCounters counters_;  ///< of the stiffness output, the pipeline's own
  EventLog events_;                   ///< resets, stiffness messages the sink refused
  mutable PipelineCounters merged_;   ///< what counters() returns
  std::unique_ptr<InputGate> gate_;
  std::unique_ptr<StiffnessEstimator> estimator_;
  std::unique_ptr<CalibrationStage> calibration_;
  std::unique_ptr<ResonanceTracker> resonance_;
  std::unique_ptr<PhaseSource> phase_;
  std::unique_ptr<DynamicsStage> dynamics_;  ///< null without ~dynamics, as the consumers below
  std::unique_ptr<TeOutput> te_output_;
  std::unique_ptr<TeSpectrumStage> te_spectrum_;
  std::unique_ptr<MeshPeriodStage> mesh_periods_;
  std::unique_ptr<VibrationInput> vibration_;
  std::unique_ptr<ModalStage> modal_;  ///< after everything it reads
  double held_torque_ = 0.0;  ///< [N*m] the last accepted torque, which the calibration pairs with
  std::optional<Stamp> last_stiffness_out_;
};

}  // namespace drivetrain_stiffness

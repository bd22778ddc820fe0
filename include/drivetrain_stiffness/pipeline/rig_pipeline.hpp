// The online estimation pipeline, free of ROS: what the node, the nodelet and the bag replay tool
// all run. It takes the rig's inputs (torque, preload, encoder readings) with their stamps and the
// caller's clock, and composes the stages under pipeline/ (docs/pipeline.md): the input gate (the
// time, value, frame and transport rules), the stiffness estimator, the phase source, the
// dynamics with their sample consumers (TE output, TE spectrum, mesh-period statistics), the
// resonance and the calibration; every output goes to a PipelineSink. It never reads a clock:
// stamps and "now" are arguments, so a replay with the recorded stamps is bit-identical to the
// live run that saw the same inputs in the same order.
//
// The rules, by name: docs/ros_api.md, "Time and input rules". Every input is counted, accepted
// or refused, never both. Errors: only the library's own (drivetrain_stiffness::Error,
// core/errors.hpp) are caught and counted with their reason in last_event (rejected inputs,
// dynamics_errors, calibration_errors, stiffness_refused); a programming error such as
// std::logic_error passes through to the caller. An input marked Backlog::kShed passes every rule
// and drives the dynamics at its stamp, but skips the stiffness update and message (stiffness_shed).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/core/motion.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"
#include "drivetrain_stiffness/pipeline/dynamics_stage.hpp"
#include "drivetrain_stiffness/pipeline/input_gate.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/mesh_period_stage.hpp"
#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"
#include "drivetrain_stiffness/pipeline/resonance_tracker.hpp"
#include "drivetrain_stiffness/pipeline/runtime_settings.hpp"
#include "drivetrain_stiffness/pipeline/te_output.hpp"
#include "drivetrain_stiffness/pipeline/te_spectrum_stage.hpp"

namespace drivetrain_stiffness {

class RigPipeline {
 public:
  /// Throws InvalidInput naming the field for an invalid rig, option or setting. Without settings:
  /// RuntimeSettings::forRig (the gearbox's damping, the other defaults).
  RigPipeline(const RigConfig& rig, const PipelineOptions& options, const RuntimeSettings& settings);
  RigPipeline(const RigConfig& rig, const PipelineOptions& options);

  /// The caller's clock (ROS time now, or the bag's record time). Returns true if it went back
  /// by more than ~clock_jump_back and everything was reset.
  bool observeClock(Stamp now, PipelineSink& sink);
  InputOutcome torque(Stamp stamp, double torque, PipelineSink& sink, const InputOrigin& origin = {},
                      Backlog backlog = Backlog::kNone);
  InputOutcome preload(Stamp stamp, const std::vector<PreloadSetting>& settings, PipelineSink& sink,
                       const InputOrigin& origin = {});
  /// One encoder reading (the encoder rule). Refusals name the field: a non-finite angle, a speed
  /// beyond +-1e5 rpm.
  InputOutcome motion(Stamp stamp, const MotionInput& reading, PipelineSink& sink, const InputOrigin& origin = {});
  /// A joint_states message stamped `stamp` that the caller could not convert (no pinion joint):
  /// counted as a rejected reading with an invalid value, `reason` in last_event, `found` (the
  /// message's joint names) in the tally.
  InputOutcome motionRefused(Stamp stamp, const std::string& reason, const InputOrigin& origin = {},
                             std::string_view found = {});
  /// "nominal", "encoders" or "nominal (encoders timed out)": what drives the mesh phase now.
  const char* phaseSource() const;
  /// [s] from the last accepted encoder reading to `now` while the encoders drive the phase
  /// (nullopt otherwise). The time-out is taken on the stamps of inputs, so with every
  /// input stopped the phase source stays "encoders": /diagnostics shows this age on the clock.
  std::optional<double> encoderSilence(Stamp now) const;
  /// Publishers whose drops cannot be seen (they leave header.seq constant), over every stream.
  std::size_t unnumberedPublishers() const { return gate_->unnumberedPublishers(); }
  /// Back to the configured preloads, zero torque, dynamics restarted at the next torque input.
  void reset(const std::string& reason);

  /// New run-time settings (dynamic_reconfigure), validated and applied whole, or refused
  /// (InvalidInput naming the field) with nothing changed. The dynamics keep their state; a damping
  /// change rebuilds them and republishes the resonance at the next input.
  void apply(const RuntimeSettings& settings);
  const RuntimeSettings& settings() const { return settings_; }

  const PipelineCounters& counters() const { return counters_; }
  /// Every refused input by stream and reason (the counters count them; this says what and why).
  const RefusalTally& refusals() const { return gate_->refusals(); }
  const PipelineOptions& options() const { return options_; }
  const StiffnessEstimator& estimator() const { return *estimator_; }
  const DynamicsEstimator* dynamics() const { return dynamics_ ? &dynamics_->model() : nullptr; }
  /// The live calibration (the calibration rule), or null without a calibration block or with ~calibrate off.
  const Calibrator* calibrator() const { return calibration_->calibrator(); }
  /// The rig as the pipeline runs it (shared read only with the estimator, the dynamics and the
  /// calibration): the gearbox with the nominal speed and the start-up damping; the current damping
  /// is settings()'.
  const RigConfig& rig() const { return *rig_; }
  const std::optional<ResonanceEstimate>& lastResonance() const { return resonance_->last(); }
  /// Pinion angle at `stamp` [rad]: the last encoder reading extrapolated at its speed, or the
  /// nominal speed's angle since the dynamics origin (plus ~mesh_phase_offset as an angle).
  double pinionAngle(Stamp stamp) const;
  /// pinionAngle less the ~mesh_phase_offset it carries once encoders anchored it: the angle the
  /// encoders count, extrapolated (what the tf frames draw).
  double encoderPinionAngle(Stamp stamp) const;

 private:
  /// `validate` (the value rules), the time rules, then `update` (transactional: the new estimate,
  /// or nullptr for no stiffness message); counts the outcome, publishes the stiffness.
  template <typename Validate, typename Update>
  InputOutcome take(InputStream stream, Stamp stamp, PipelineSink& sink, Validate validate, Update update);
  /// The stiffness message (throttled by ~stiffness_rate on stamps), then pushStiffness.
  void afterUpdate(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink);
  /// The new bearing stiffness to the dynamics from `stamp` on, then the resonance estimate.
  void pushStiffness(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink);
  void acceptMotion(Stamp stamp, const MotionInput& reading, PipelineSink& sink);
  /// The encoders' time-out at `stamp`: the dynamics run to it, then follow the nominal phase.
  void checkMotionTimeout(Stamp stamp, PipelineSink& sink);

  std::shared_ptr<const RigConfig> rig_;  ///< first: the members below share it
  PipelineOptions options_;
  RuntimeSettings settings_;
  PipelineCounters counters_;  ///< before the stages, which count in it
  std::unique_ptr<InputGate> gate_;
  std::unique_ptr<StiffnessEstimator> estimator_;
  std::unique_ptr<CalibrationStage> calibration_;
  std::unique_ptr<ResonanceTracker> resonance_;
  std::unique_ptr<PhaseSource> phase_;
  std::unique_ptr<DynamicsStage> dynamics_;  ///< null without ~dynamics, as the three consumers below
  std::unique_ptr<TeOutput> te_output_;
  std::unique_ptr<TeSpectrumStage> te_spectrum_;
  std::unique_ptr<MeshPeriodStage> mesh_periods_;
  double held_torque_ = 0.0;  ///< [N*m] what the calibration pairs readings with
  std::optional<Stamp> last_stiffness_out_;
};

}  // namespace drivetrain_stiffness

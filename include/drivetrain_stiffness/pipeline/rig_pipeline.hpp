// The online estimation pipeline, free of ROS: what the node, the nodelet and the bag replay tool
// all run. It takes the rig's inputs (torque, preload) with their stamps and the caller's clock,
// applies the time and value rules below, keeps the bearing and mesh stiffness up to date
// (StiffnessEstimator), integrates the 3-DOF dynamics between torque inputs (DynamicsEstimator),
// refreshes the resonance estimate and the sliding TE spectrum, and hands every output to a sink.
// It never reads a clock: stamps and "now" are arguments, so a replay with the recorded stamps is
// bit-identical to the live run that saw the same inputs in the same order.
//
// Time rules (docs/ros_api.md, "Time and input rules"):
//  1. A zero stamp is rejected (the publisher forgot to stamp; its time is unknown).
//  2. A torque stamp earlier than the last accepted one by at most ~stamp_jump_back is out of order:
//     rejected (the dynamics cannot integrate backwards). Earlier by more: the source restarted
//     (a looping or re-recorded bag): full reset, then the input is accepted. Values are checked
//     before stamps, so a bad value never causes a reset.
//  3. Equal stamps (a burst) are accepted: no time passes; the last torque is the one held.
//  4. A forward gap longer than ~max_gap restarts the dynamics: the first input after it stops
//     them before anything it carries is applied (a bearing stiffness, a motion), and the next
//     torque input restarts them with it.
//  5. The caller's clock (ROS time, or the bag's record time in the replay) going back by more
//     than ~clock_jump_back resets everything (tf2's and robot_localization's rule for looped bags),
//     unless the accepted stamps already restarted in the new timeline (rule 2 came first).
//  6. Preload stamps follow rules 1, 2 and 5 on their own stream; an older preload never overrides
//     a newer one.
//  7. A stamp outside ROS time (negative, or past 2106-02-07, uint32 seconds) is rejected: no
//     output could carry it.
//  8. A failed integration (dynamics_errors) restarts the model at that input.
//  9. joint_states (the rig's encoders, MotionInput) follow rules 1, 2, 5 and 7 on their own stream.
//     From the first accepted reading the measured pinion angle drives the mesh phase and its
//     velocity the speed (phase source "encoders"); no reading for ~motion_timeout falls back to
//     ~pinion_speed_rpm from the phase extrapolated to that moment (counted, phase source
//     "nominal (encoders timed out)") until the next reading. A gear angle off the tooth ratio by
//     more than ~gear_ratio_tolerance is counted and reported (a slip or a wrong joint mapping).
// 10. Every input takes effect at its own stamp: the dynamics are integrated up to it with what was
//     held before (torque, bearing stiffness, motion), then the input is applied. An input stamped
//     before the dynamics' time (another stream got there first) applies from that time.
// 11. With a calibration block in the gearbox (and ~calibrate), each accepted reading that carries
//     the gear joint gives the measured TE r_b,p theta_p + r_b,g theta_g to the Calibrator
//     (calibration/calibrator.hpp) with the torque held at its stamp; a reading that follows a
//     break (a time-out, a reset) starts a new window. Its outputs go to the sink.
// Value rules: NaN, Inf, negative and absurd values are rejected by the core classes
// (InvalidInput naming the field); the state is left as it was. A torque whose header.frame_id is
// not ~torque_frame is rejected before its value is read (the sign of torque.z selects the loaded
// flank, and only that frame says which way is positive). Every input is counted.
// Errors: the pipeline catches the library's own exceptions only (drivetrain_stiffness::Error,
// core/errors.hpp: InvalidInput, UnreachableLoad, UnstableIntegration), and counts each (rejected
// inputs, dynamics_errors, calibration_errors, stiffness_refused) with its reason in last_event; an
// input is either accepted or rejected, never both (a refused output is the output's count). Anything else, a
// programming error such as std::logic_error or std::out_of_range, passes through to the caller.
// Transport rules: messages a numbering publisher sent that never arrived are counted as dropped
// (SequenceGaps). An input the caller marks as backlogged (it waited too long in the subscriber
// queue) passes every rule and drives the dynamics at its stamp, but skips the stiffness update
// and message (counted as shed), so an overloaded node catches up instead of overflowing its queue.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/motion.hpp"
#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"
#include "drivetrain_stiffness/pipeline/dynamics_stage.hpp"
#include "drivetrain_stiffness/pipeline/mesh_period_stage.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"
#include "drivetrain_stiffness/pipeline/resonance_tracker.hpp"
#include "drivetrain_stiffness/pipeline/runtime_settings.hpp"
#include "drivetrain_stiffness/pipeline/sequence_gaps.hpp"
#include "drivetrain_stiffness/pipeline/te_output.hpp"
#include "drivetrain_stiffness/pipeline/te_spectrum_stage.hpp"
#include "drivetrain_stiffness/spectral/sliding_spectrum.hpp"

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
  /// One encoder reading (rule 9). Refusals name the field: a non-finite angle, a speed beyond
  /// +-1e5 rpm.
  InputOutcome motion(Stamp stamp, const MotionInput& reading, PipelineSink& sink, const InputOrigin& origin = {});
  /// A joint_states message stamped `stamp` that the caller could not convert (no pinion joint):
  /// counted as a rejected reading with an invalid value, `reason` in last_event, `found` (the
  /// message's joint names) in the tally.
  InputOutcome motionRefused(Stamp stamp, const std::string& reason, const InputOrigin& origin = {},
                             std::string_view found = {});
  /// "nominal", "encoders" or "nominal (encoders timed out)": what drives the mesh phase now.
  const char* phaseSource() const;
  /// [s] from the last accepted encoder reading to `now` while the encoders drive the phase
  /// (nullopt otherwise). The time-out (rule 9) is taken on the stamps of inputs, so with every
  /// input stopped the phase source stays "encoders": /diagnostics shows this age on the clock.
  std::optional<double> encoderSilence(Stamp now) const;
  /// Publishers whose drops cannot be seen (they leave header.seq constant), over both streams.
  std::size_t unnumberedPublishers() const {
    return torque_seq_.unnumberedPublishers() + preload_seq_.unnumberedPublishers() + motion_seq_.unnumberedPublishers();
  }
  /// Back to the configured preloads, zero torque, dynamics restarted at the next torque input.
  void reset(const std::string& reason);

  /// New run-time settings (dynamic_reconfigure), validated and applied whole, or refused
  /// (InvalidInput naming the field) with nothing changed. The dynamics keep their state; a damping
  /// change rebuilds them and republishes the resonance at the next input.
  void apply(const RuntimeSettings& settings);
  const RuntimeSettings& settings() const { return settings_; }

  const PipelineCounters& counters() const { return counters_; }
  /// Every refused input by stream and reason (the counters count them; this says what and why).
  const RefusalTally& refusals() const { return refusals_; }
  const PipelineOptions& options() const { return options_; }
  const StiffnessEstimator& estimator() const { return *estimator_; }
  const DynamicsEstimator* dynamics() const { return dynamics_ ? &dynamics_->model() : nullptr; }
  /// The live calibration (rule 11), or null without a calibration block or with ~calibrate off.
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
  /// Counts a refused input (its stream's counter `rejected`, the reason's, the tally) and says why
  /// in last_event; `found` is the offending value for the tally (a frame id, the joint names).
  InputOutcome reject(InputOutcome why, InputStream stream, Stamp stamp, const std::string& reason,
                      std::uint64_t& rejected, std::string_view found = {});
  /// Rules 1, 2 and 5 for one stream; returns kAccepted or the rejection (counted by the caller).
  InputOutcome checkStamp(Stamp stamp, std::optional<Stamp>& last, InputStream stream, PipelineSink& sink);
  /// `validate` (the value checks), the stamp rules, then `update` (a StiffnessEstimator call that
  /// returns the new estimate, or nullptr for a shed input);
  /// counts and reports the outcome.
  template <typename Validate, typename Update>
  InputOutcome apply(InputStream stream, Stamp stamp, std::optional<Stamp>& last, std::uint64_t& accepted,
                     std::uint64_t& rejected, PipelineSink& sink, Validate validate, Update update);
  void afterUpdate(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink);
  /// The new bearing stiffness from `stamp` on, then the resonance estimate.
  void pushStiffness(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink);
  void acceptMotion(Stamp stamp, const MotionInput& reading, PipelineSink& sink);
  /// Rule 9's fall-back when the last reading is older than ~motion_timeout at `stamp`.
  void checkMotionTimeout(Stamp stamp, PipelineSink& sink);

  std::shared_ptr<const RigConfig> rig_;  ///< first: the members below share it
  PipelineOptions options_;
  RuntimeSettings settings_;
  std::unique_ptr<StiffnessEstimator> estimator_;
  std::unique_ptr<CalibrationStage> calibration_;
  std::unique_ptr<ResonanceTracker> resonance_;
  std::unique_ptr<PhaseSource> phase_;
  std::unique_ptr<DynamicsStage> dynamics_;  ///< null without ~dynamics, as the three consumers below
  std::unique_ptr<TeOutput> te_output_;
  std::unique_ptr<TeSpectrumStage> te_spectrum_;
  std::unique_ptr<MeshPeriodStage> mesh_periods_;
  PipelineCounters counters_;
  RefusalTally refusals_;
  SequenceGaps torque_seq_, preload_seq_, motion_seq_;
  std::optional<Stamp> last_motion_;
  double held_torque_ = 0.0;
  std::optional<Stamp> last_torque_, last_preload_, last_clock_, last_stiffness_out_;
  bool stamps_restarted_ = false;  ///< rule 2 reset since the last clock jump (rule 5 then skips one)
};

}  // namespace drivetrain_stiffness

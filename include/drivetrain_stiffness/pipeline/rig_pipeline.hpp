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
#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"
#include "drivetrain_stiffness/pipeline/runtime_settings.hpp"
#include "drivetrain_stiffness/pipeline/sequence_gaps.hpp"
#include "drivetrain_stiffness/spectral/sliding_spectrum.hpp"

namespace drivetrain_stiffness {

/// Settings of the pipeline (the node's private parameters). validate() names the field and value.
struct PipelineOptions {
  EstimatorLimits limits = onlineLimits();  ///< limits.load_tolerance: ~bearing_load_tolerance
  static EstimatorLimits onlineLimits() {
    EstimatorLimits l;
    // 1e-3 of the support load: the stiffness lags by ~3e-4, far inside the 1 % at which the
    // dynamics take up a change (on a 1 % grid) and the resonance republishes; ripple no longer
    // re-solves every bearing.
    l.load_tolerance = 1e-3;
    return l;
  }
  bool dynamics = true;              ///< integrate the 3-DOF model (needs the gearbox's dynamics block)
  double output_rate = 1000.0;       ///< [Hz] transmission_error rate, rounded to divide the mesh period
  double max_gap = 1.0;              ///< [s] a longer forward input gap restarts the dynamics
  double stamp_jump_back = 1.0;      ///< [s] a stamp further back than this restarts everything
  /// [s] the clock going back by more than this resets everything. 1 s tells a looping bag (it
  /// jumps back by its length, seconds to hours) from a clock correction on a live rig: ntpd steps
  /// offsets over 0.128 s (its default step threshold) and slews smaller ones; chrony's usual
  /// `makestep 1.0 3` steps only by more than 1 s and only in its first three updates. A smaller
  /// step back keeps the state; inputs stamped before the last accepted one are then rejected as
  /// out of order (rule 2, counted) until the clock has caught up.
  double clock_jump_back = 1.0;
  double resonance_threshold = 0.01; ///< [-] relative frequency change that republishes resonance
  int spectrum_window = 1024;        ///< [samples] TE spectrum window
  int spectrum_hop = 256;            ///< [samples] between spectra
  double pinion_speed_rpm = 1000.0;  ///< [rpm] nominal speed for the mesh phase
  std::string torque_frame;          ///< required header.frame_id of torque inputs; empty = any
  double mesh_phase_offset = 0.0;    ///< [-] mesh phase at measured pinion angle 0 (where a drive pair enters contact)
  double motion_timeout = 0.1;       ///< [s] no joint_states for this long: back to ~pinion_speed_rpm
  double gear_ratio_tolerance = 0.01;  ///< [rad] gear angle off -(z_p/z_g) pinion angle by more: reported
  int motion_slices = 256;           ///< slices per mesh period of the measured-motion dynamics
  /// Calibrate against the encoders' TE when the gearbox has a calibration block (rule 11).
  bool calibrate = true;
  void validate() const;
};

/// The resonance estimate at an operating point.
struct ResonanceEstimate {
  std::array<Mode, 3> modes;
  bool floquet_valid = false;
  double floquet_margin = 0.0;  ///< 1 - max |Floquet multiplier| (0 when not valid)
};

/// Statistics of the dynamic TE and the mesh force over a block of whole mesh periods (issue 12):
/// what the mesh does, not what the output grid happens to see (at 1000 rpm with 20 teeth the
/// 1 kHz grid samples the 333 Hz mesh at three phases, one of them on the tooth switch). A block
/// runs from the first output sample at or after a mesh-period boundary (the mesh phase passing an
/// integer, forward or backward) to the first sample at or after the boundary `periods` whole
/// periods further on, net (a reversal inside the block lengthens it). periods = max(1,
/// ceil(10 x output interval x |mesh frequency|)) at the block's start, so that a block spans at
/// least ~10 output samples at any speed. (Named apart from the message drivetrain_stiffness/
/// MeshPeriodStats, which shares the namespace.) Estimators (RigPipeline::MeshPeriodAccumulator):
///  - te_mean: the trapezoidal (time-weighted) mean of the samples over [start, end]. The dynamic
///    TE is continuous in time (it is a function of the state), so the trapezoid is a quadrature
///    of a continuous periodic function and converges with the samples per period; but it settles
///    within a fraction of an output interval after each tooth switch, a near-jump that a few
///    phases per period cannot place: on the seed at 1000 rpm it is off by 14 % of the true mean
///    at 1 kHz (3 samples per period), 0.5 % at 10 kHz (test_mesh_period_stats.cpp). No exact
///    balance gives it (the torsional coordinate has no restoring force but the mesh's); an exact
///    one would need the integral of the state from the propagators (not done).
///  - mesh_force_mean: NOT the samples' mean. The mesh force jumps at every tooth switch (the mesh
///    stiffness does) and a sample on the switch reports its right limit, so any quadrature of a
///    few samples per period is biased (+19 % at 1000 rpm / 1 kHz on the seed). It is the exact
///    momentum balance of the relative mesh coordinate, m_s x'' = F_drive - F_mesh, integrated over
///    the block: mean F_mesh = mean F_drive - m_s (v(end) - v(start)) / duration, with F_drive =
///    T / r_b,p (the dynamics' quasi-static load) averaged by the trapezoid of the held torque
///    (exact for a torque constant over the block; a step inside it is off by at most
///    |dT| / r_b,p x output interval / (2 duration)). With the quasi_static fidelity (m_s -> 0)
///    the term in v is left out.
///  - *_rms: the samples' own spread about their trapezoidal mean, sqrt(mean(x^2) - mean(x)^2)
///    (time-weighted); *_peak_to_peak: max - min over the samples in [start, end]. Both see only
///    the sampled phases.
///  - mesh_frequency: net mesh turns / duration [Hz] (signed: negative in reverse); torque: the
///    trapezoidal mean of the held torque [N*m].
struct MeshPeriodStatistics {
  Stamp start, end;               ///< the block's first and last output samples
  double duration = 0.0;          ///< end - start [s]
  std::uint32_t periods = 0;      ///< whole mesh periods in the block (net)
  std::uint32_t samples = 0;      ///< output samples in [start, end) (the end sample starts the next block)
  double te_mean = 0.0, te_rms = 0.0, te_peak_to_peak = 0.0;                          ///< [m]
  double mesh_force_mean = 0.0, mesh_force_rms = 0.0, mesh_force_peak_to_peak = 0.0;  ///< [N]
  double mesh_frequency = 0.0;    ///< [Hz]
  double torque = 0.0;            ///< [N*m]
};

/// What the tf frames and markers of a transmission-error sample need besides the sample: plain
/// values of that moment, so that a sink never asks the pipeline back in the middle of an advance.
struct SampleContext {
  /// [rad] at the sample's stamp, as the encoders count it (RigPipeline::encoderPinionAngle: without
  /// the ~mesh_phase_offset that the mesh phase carries), or the nominal angle without encoders.
  double pinion_angle = 0.0;
  /// The last published resonance estimate, null when there is none since the last reset; points
  /// at the pipeline's copy, valid during the call only.
  const ResonanceEstimate* resonance = nullptr;
};

/// The TE spectrum's strongest lines over the sliding window, copied out of it (fixed storage: no
/// allocation per spectrum).
struct SpectrumPeaks {
  static constexpr std::size_t kMaxPeaks = 3;  ///< the lines the pipeline keeps (te_spectrum)
  std::array<SpectralPeak, kMaxPeaks> peaks{};  ///< the first `count`, strongest first
  std::size_t count = 0;
  double resolution = 0.0;      ///< [Hz] bin spacing, 1 / window_seconds
  double window_seconds = 0.0;  ///< [s]
};

/// Receives the pipeline's outputs as plain values; every method is optional. A sink may throw the
/// library's own Error (a message it refuses, e.g. a non-finite number): the pipeline counts it.
class PipelineSink {
 public:
  virtual ~PipelineSink() = default;
  /// After an accepted input (throttled to ~stiffness_rate); stamp = the input's. `bands`: the
  /// calibrated stiffness at the estimate's torque with its 95 % bounds, or without a calibration
  /// the drawing's model (mesh: estimate.mesh.mean; bearings: the shafts' radial stiffness) with
  /// bounds of zero width; the natural frequencies are not filled.
  virtual void stiffness(Stamp /*stamp*/, const StiffnessEstimate& /*estimate*/, const CalibrationBands& /*bands*/) {}
  /// One transmission-error sample on the output grid, at `stamp` (exact; sample.t = stamp.toSec()).
  virtual void transmissionError(Stamp /*stamp*/, const DynamicsSample& /*sample*/, const SampleContext& /*context*/) {}
  /// New TE spectrum peaks; stamp of the newest sample in the window.
  virtual void spectrum(Stamp /*stamp*/, const SpectrumPeaks& /*peaks*/) {}
  /// The resonance estimate moved by more than the threshold (or after a reset); stamp = the
  /// input's. `bands`: the calibrated stiffness and natural frequencies at the current torque with
  /// their 95 % bounds, or without a calibration the estimate's frequencies with bounds of zero
  /// width (the stiffness entries then unfilled).
  virtual void resonance(Stamp /*stamp*/, const ResonanceEstimate& /*estimate*/, const CalibrationBands& /*bands*/) {}
  /// One encoder reading's measured TE (baseline and shaft orders removed) beside the calibrated
  /// model's; stamp = the reading's (rule 11).
  virtual void measuredTe(Stamp /*stamp*/, const MeasuredTeSample& /*sample*/) {}
  /// The calibration after a closed window (every window, whatever its outcome); stamp = the
  /// reading that closed it.
  virtual void calibration(Stamp /*stamp*/, const CalibrationEstimate& /*estimate*/) {}
  /// One block of whole mesh periods closed (MeshPeriodStatistics); stamp = its end sample's.
  virtual void meshPeriod(Stamp /*stamp*/, const MeshPeriodStatistics& /*stats*/) {}
};

/// Counters of everything the pipeline saw; nothing is dropped without being counted here.
struct PipelineCounters {
  std::uint64_t accepted_torque = 0, rejected_torque = 0;
  std::uint64_t accepted_preload = 0, rejected_preload = 0;
  std::uint64_t zero_stamps = 0, out_of_order = 0, invalid_values = 0, unreachable_loads = 0;
  std::uint64_t wrong_frames = 0, stamps_out_of_range = 0;
  std::uint64_t dropped_torque = 0, dropped_preload = 0;  ///< numbered messages that never arrived
  std::uint64_t accepted_motion = 0, rejected_motion = 0, dropped_motion = 0;  ///< joint_states
  std::uint64_t motion_timeouts = 0, gear_ratio_mismatches = 0;
  std::uint64_t stiffness_shed = 0;  ///< backlogged torque inputs: dynamics only, no stiffness update
  std::uint64_t clock_resets = 0, stamp_resets = 0, gap_restarts = 0;
  std::uint64_t dynamics_errors = 0;
  std::uint64_t stiffness_out = 0, stiffness_coalesced = 0;  ///< published, and skipped by ~stiffness_rate
  std::uint64_t stiffness_refused = 0;  ///< stiffness messages the sink refused (its reason in last_event)
  std::uint64_t te_out = 0, spectra_out = 0, resonance_out = 0;
  std::uint64_t modal_updates = 0;  ///< modal analyses actually run (see RigPipeline::updateResonance)
  std::uint64_t measured_te_out = 0, calibration_out = 0;  ///< published (rule 11)
  std::uint64_t mesh_period_stats_out = 0;  ///< blocks of whole mesh periods published (MeshPeriodStatistics)
  std::uint64_t calibration_errors = 0;  ///< windows the calibration could not evaluate (last_event says why)
  double simulated_s = 0.0;         ///< model time integrated
  std::string last_event;           ///< last rejection or reset, with its reason
};

/// The counters by the names /diagnostics and drivetrain_replay's summary use (one list for both).
std::vector<std::pair<std::string, std::uint64_t>> namedCounters(const PipelineCounters& c);

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
  const DynamicsEstimator* dynamics() const { return dynamics_.get(); }
  /// The live calibration (rule 11), or null without a calibration block or with ~calibrate off.
  const Calibrator* calibrator() const { return calibrator_.get(); }
  /// The rig as the pipeline runs it (shared read only with the estimator, the dynamics and the
  /// calibration): the gearbox with the nominal speed and the start-up damping; the current damping
  /// is settings()'.
  const RigConfig& rig() const { return *rig_; }
  const std::optional<ResonanceEstimate>& lastResonance() const { return last_resonance_; }
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
  void advanceDynamics(Stamp stamp, double torque, PipelineSink& sink);
  /// Integrates the dynamics up to `stamp` (rule 10) with what is held; false if not running or
  /// already past it.
  bool advanceDynamicsTo(Stamp stamp, PipelineSink& sink);
  /// advanceTo(t) handing each sample to the sink and the TE spectrum (throws what advanceTo throws).
  void emitUpTo(double t, PipelineSink& sink);
  /// The new bearing stiffness from `stamp` on, then the resonance estimate.
  void pushStiffness(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink);
  void acceptMotion(Stamp stamp, const MotionInput& reading, PipelineSink& sink);
  double ratio() const;          ///< z_p / z_g
  int teeth(int shaft) const;
  /// Rule 9's fall-back when the last reading is older than ~motion_timeout at `stamp`.
  void checkMotionTimeout(Stamp stamp, PipelineSink& sink);
  /// The dynamics follow the pinion angle model (anchor) from `stamp` on.
  void followAnchor(Stamp stamp);
  double meshTurns(double pinion_angle) const;
  /// Rule 4: an input more than ~max_gap after the dynamics' time stops them (counted); the next
  /// torque input restarts them.
  void stopAfterGap(Stamp stamp);
  /// Dynamics at static equilibrium under `torque` from `stamp` on (new epoch, empty spectrum).
  void restartDynamics(Stamp stamp, double torque);
  void updateResonance(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink);
  /// The sinks' bands (PipelineSink::stiffness, ::resonance): the calibration's, or the drawing's
  /// model with bounds of zero width.
  CalibrationBands stiffnessBands(const StiffnessEstimate& estimate) const;
  CalibrationBands resonanceBands(const ResonanceEstimate& estimate) const;
  SpectrumPeaks spectrum_peaks_;  ///< the sink's copy of the spectrum (reused)
  /// A failure of the dynamics or the resonance on the library's own error (errors.hpp): counted
  /// in dynamics_errors with `where` and the reason in last_event. Nothing wider is caught: a
  /// programming error leaves the pipeline.
  void dynamicsError(const std::string& where, const Error& e);

  /// The running block of MeshPeriodStatistics (plain values: no allocation per sample).
  struct MeshPeriodAccumulator {
    bool have_last = false, in_block = false;
    Stamp last_stamp;
    double last_turns = 0.0;        ///< unwrapped mesh phase of the last sample [turns]
    double last_te = 0.0, last_force = 0.0, last_torque = 0.0;
    double boundary = 0.0;          ///< the integer mesh phase the block started at
    std::uint32_t periods = 0, samples = 0;
    Stamp start;
    double start_turns = 0.0, start_velocity = 0.0;
    double te_ref = 0.0, force_ref = 0.0;  ///< the start values: sums of x - ref (no cancellation)
    double te_sum = 0.0, te_sq = 0.0, force_sum = 0.0, force_sq = 0.0, torque_sum = 0.0;  ///< trapezoid x dt
    double te_min = 0.0, te_max = 0.0, force_min = 0.0, force_max = 0.0;
  };
  /// One output sample into the running block; publishes a closed block. `mesh_frequency` [Hz]:
  /// the dynamics' during this advance (unwraps the phase at any speed).
  void meshPeriodSample(Stamp stamp, const DynamicsSample& s, double mesh_frequency, PipelineSink& sink);
  void startMeshBlock(Stamp stamp, const DynamicsSample& s, double turns, double boundary, double mesh_frequency);
  MeshPeriodAccumulator mesh_block_;
  double advance_mesh_frequency_ = 0.0;  ///< [Hz] the dynamics' during the current emitUpTo

  std::shared_ptr<const RigConfig> rig_;  ///< first: the members below share it
  PipelineOptions options_;
  RuntimeSettings settings_;
  std::unique_ptr<StiffnessEstimator> estimator_;
  std::unique_ptr<DynamicsEstimator> dynamics_;
  std::unique_ptr<SlidingSpectrum> te_spectrum_;
  std::unique_ptr<Calibrator> calibrator_;
  MeasuredTeSample measured_te_;  ///< the calibrator's per-reading output (reused: no allocation)
  PipelineCounters counters_;
  RefusalTally refusals_;
  SequenceGaps torque_seq_, preload_seq_, motion_seq_;
  std::optional<Stamp> last_motion_;
  /// The pinion angle model: angle(stamp) = angle + speed (stamp - stamp) [rad, rad/s], offset included.
  struct AngleAnchor {
    Stamp stamp;
    double angle = 0.0, speed = 0.0;
  };
  std::optional<AngleAnchor> anchor_;  ///< set by encoder readings (and their time-out); empty: nominal
  bool encoders_ = false;              ///< the anchor comes from a reading (not a time-out)
  /// The last reading, unwrapped, for the next one's unwrapping, differentiation and ratio check.
  struct Reading {
    Stamp stamp;
    double pinion = 0.0, speed = 0.0;
    std::optional<double> gear, gear_reference;
  };
  std::optional<Reading> reading_;
  /// Rule 11 for an accepted reading; `continuous`: it follows the last one without a break.
  void calibrate(Stamp stamp, const Reading& reading, bool continuous, PipelineSink& sink);
  /// A window the calibration could not evaluate (the library's own errors only): counted, reason
  /// in last_event, the window dropped.
  void calibrationError(const Error& e);
  /// The reading unwrapped against `last` (null: none recent), its speed measured or differentiated.
  Reading unwrapReading(Stamp stamp, const MotionInput& reading, const Reading* last) const;
  double held_torque_ = 0.0;
  std::optional<Stamp> last_torque_, last_preload_, last_clock_, last_stiffness_out_;
  std::optional<Stamp> angle_origin_;
  bool stamps_restarted_ = false;  ///< rule 2 reset since the last clock jump (rule 5 then skips one)
  /// The dynamics run on seconds since this stamp (the last restart): at a 1.7e9 s epoch a double
  /// resolves only 2.4e-7 s, enough to put an input exactly on a grid point one sample short.
  Stamp dynamics_epoch_;
  double pinion_speed_ = 0.0;  ///< [rad/s]
  std::optional<ResonanceEstimate> last_resonance_;
  /// Spring stiffnesses (bearing per shaft, mean mesh) at the last published resonance.
  std::array<double, 3> springs_at_resonance_{};
};

}  // namespace drivetrain_stiffness

// The input gate: the time, frame and transport rules every input passes before it is taken
// (docs/ros_api.md "Time and input rules", each rule a function named as there), the joint_states
// value rules, and the counting of every input accepted, refused (with RefusalTally) or lost on
// the way (SequenceGaps). It decides; RigPipeline resets when it says the source or the clock
// restarted. ROS-free.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "drivetrain_stiffness/core/motion.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"
#include "drivetrain_stiffness/pipeline/sequence_gaps.hpp"

namespace drivetrain_stiffness {

class InputGate {
 public:
  /// Uses ~stamp_jump_back, ~clock_jump_back [s] and ~torque_frame of `options` (validated);
  /// counts in `counters` (kept by reference).
  InputGate(const PipelineOptions& options, PipelineCounters& counters);

  // --- The rules, pure ---
  /// The zero-stamp rule: the publisher forgot to stamp.
  static bool isZeroStamp(Stamp stamp) { return stamp.isZero(); }
  /// The stamp-range rule: negative, or past what ros::Time holds (2106-02-07).
  static bool outsideRosTime(Stamp stamp) { return !stamp.inRosRange(); }
  /// The out-of-order rule: earlier than `last` by at most ~stamp_jump_back (equal stamps, a
  /// burst, are in order).
  bool isOutOfOrder(Stamp stamp, std::optional<Stamp> last) const;
  /// The source-restart rule: earlier than `last` by more than ~stamp_jump_back.
  bool sourceRestarted(Stamp stamp, std::optional<Stamp> last) const;
  /// The frame rule: a torque frame other than ~torque_frame (a leading '/' ignored; none set: any).
  bool isWrongFrame(std::string_view frame_id) const;
  /// The clock-jump rule: the caller's clock at `now` went back by more than ~clock_jump_back.
  bool clockJumpedBack(Stamp now) const;
  /// The joint_states value rules: finite angles, a velocity within +-1e5 rpm (InvalidInput
  /// naming the field otherwise).
  static void validateReading(const MotionInput& reading);

  // --- One input through the rules, counted ---
  /// The messages `origin`'s publisher numbered on `stream` that never arrived, counted as dropped.
  void countDrops(InputStream stream, const InputOrigin& origin);
  /// The frame rule for a torque input: kWrongFrame (refused and counted) or kAccepted.
  InputOutcome checkFrame(Stamp stamp, const InputOrigin& origin);
  /// The time rules on `stream`'s own stamps: kAccepted, or kZeroStamp, kStampRange, kOutOfOrder
  /// (not yet counted: reject()). A source restart passes; see noteSourceRestart.
  InputOutcome checkStamp(InputStream stream, Stamp stamp) const;
  /// When the source restarted at `stamp`: counted (stamp_resets), remembered for the clock-jump
  /// rule, and the reason to reset everything returned; nullopt otherwise.
  std::optional<std::string> noteSourceRestart(InputStream stream, Stamp stamp);
  /// The caller's clock at `now` (remembered): the reason to reset everything when it jumped back
  /// (counted in clock_resets), unless the stamps already restarted since the last jump.
  std::optional<std::string> observeClock(Stamp now);
  /// Counts a refused input (its stream's, its reason's, the tally with `found`, the offending
  /// value) and says why in last_event; returns `why`.
  InputOutcome reject(InputOutcome why, InputStream stream, Stamp stamp, const std::string& reason,
                      std::string_view found = {});
  /// An input taken: counted, its stamp the stream's last.
  void accept(InputStream stream, Stamp stamp);
  /// Forgets every stream's last stamp (a reset); the clock is kept.
  void forgetStamps();

  const RefusalTally& refusals() const { return refusals_; }
  /// Publishers whose drops cannot be seen (they leave header.seq constant), over every stream.
  std::size_t unnumberedPublishers() const;

 private:
  struct Stream {
    SequenceGaps sequence;
    std::optional<Stamp> last;
  };
  Stream& stream(InputStream s) { return streams_[static_cast<std::size_t>(s)]; }
  const Stream& stream(InputStream s) const { return streams_[static_cast<std::size_t>(s)]; }

  double stamp_jump_back_, clock_jump_back_;
  std::string torque_frame_;
  PipelineCounters& counters_;
  RefusalTally refusals_;
  std::array<Stream, kInputStreams> streams_;
  std::optional<Stamp> last_clock_;
  bool stamps_restarted_ = false;  ///< a source restart since the last clock jump (that jump is the same)
};

}  // namespace drivetrain_stiffness

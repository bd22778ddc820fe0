// The input gate: the time, frame, transport and joint_states value rules of docs/ros_api.md, each
// a function named as there; every input counted.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "drivetrain_stiffness/core/dynamics/motion.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"
#include "drivetrain_stiffness/pipeline/sequence_gaps.hpp"
#include "drivetrain_stiffness/pipeline/stage_counters.hpp"

namespace drivetrain_stiffness {

class InputGate {
 public:
  explicit InputGate(const PipelineOptions& options);

  // --- The rules, pure ---
  /// The zero-stamp rule: the publisher forgot to stamp.
  static bool isZeroStamp(Stamp stamp) { return stamp.isZero(); }
  /// The stamp-range rule: negative, or past what ros::Time holds (2106-02-07).
  static bool outsideRosTime(Stamp stamp) { return !stamp.inRosRange(); }
  /// The out-of-order rule: earlier than `last` by at most ~stamp_jump_back.
  bool isOutOfOrder(Stamp stamp, std::optional<Stamp> last) const;
  /// The source-restart rule: earlier than `last` by more than ~stamp_jump_back.
  bool sourceRestarted(Stamp stamp, std::optional<Stamp> last) const;
  /// The frame rule: not ~torque_frame (a leading '/' ignored).
  bool isWrongFrame(std::string_view frame_id) const;
  /// The clock-jump rule: the clock went back by more than ~clock_jump_back.
  bool clockJumpedBack(Stamp now) const;
  /// The joint_states value rules; throws InvalidInput naming the field.
  static void validateReading(const MotionInput& reading);

  // --- One input through the rules, counted ---
  /// Counts as dropped what `origin`'s publisher numbered that never arrived.
  void countDrops(InputStream stream, const InputOrigin& origin);
  /// The frame rule on a torque input: kWrongFrame (refused, counted) or kAccepted.
  InputOutcome checkFrame(Stamp stamp, const InputOrigin& origin);
  /// The time rules on `stream`'s stamps; a refusal is counted by reject().
  InputOutcome checkStamp(InputStream stream, Stamp stamp) const;
  /// The source-restart rule: the reason to reset everything (counted), or nullopt.
  std::optional<std::string> noteSourceRestart(InputStream stream, Stamp stamp);
  /// The clock-jump rule at `now`: the reason to reset (counted), unless the stamps restarted.
  std::optional<std::string> observeClock(Stamp now);
  /// Counts a refusal, says why in events(); returns `why`.
  InputOutcome reject(InputOutcome why, InputStream stream, Stamp stamp, const std::string& reason,
                      std::string_view found = {});
  /// An input taken: counted, its stamp the stream's last.
  void accept(InputStream stream, Stamp stamp);
  /// Forgets every stream's last stamp (a reset); the clock is kept.
  void forgetStamps();

  const RefusalTally& refusals() const { return refusals_; }
  const GateCounters& counters() const { return counters_; }
  /// The last refusal, with its reason.
  const EventLog& events() const { return events_; }
  /// Publishers whose drops cannot be seen.
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
  GateCounters counters_;
  EventLog events_;
  RefusalTally refusals_;
  std::array<Stream, kInputStreams> streams_;
  std::optional<Stamp> last_clock_;
  bool stamps_restarted_ = false;  ///< a source restart since the last clock jump
};

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/pipeline/input_gate.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
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

InputGate::InputGate(const PipelineOptions& options)
    : stamp_jump_back_(options.stamp_jump_back),
      clock_jump_back_(options.clock_jump_back),
      torque_frame_(options.torque_frame) {}

bool InputGate::isOutOfOrder(Stamp stamp, std::optional<Stamp> last) const {
  return last && stamp < *last && secondsBetween(*last, stamp) <= stamp_jump_back_;
}

bool InputGate::sourceRestarted(Stamp stamp, std::optional<Stamp> last) const {
  return last && stamp < *last && !(secondsBetween(*last, stamp) <= stamp_jump_back_);
}

bool InputGate::isWrongFrame(std::string_view frame_id) const {
  if (torque_frame_.empty()) return false;
  // tf2 strips a leading '/' (ROS 1 frame ids may still carry one).
  const std::string_view frame =
      !frame_id.empty() && frame_id.front() == '/' ? frame_id.substr(1) : frame_id;
  return frame != torque_frame_;
}

bool InputGate::clockJumpedBack(Stamp now) const {
  return last_clock_ && secondsBetween(*last_clock_, now) > clock_jump_back_;
}

void InputGate::validateReading(const MotionInput& reading) {
  requireFinite("joint_states: pinion position", reading.pinion_angle);
  if (reading.pinion_velocity) {
    requireFinite("joint_states: pinion velocity", *reading.pinion_velocity);
    // The same bound as ~pinion_speed_rpm: +-1e5 rpm.
    if (std::abs(*reading.pinion_velocity) > 1e5 * kTwoPi / 60.0) {
      throwInvalid("joint_states: pinion velocity", *reading.pinion_velocity,
                   "beyond +-1e5 rpm (10472 rad/s)");
    }
  }
  if (reading.gear_angle) requireFinite("joint_states: gear position", *reading.gear_angle);
}

void InputGate::countDrops(InputStream s, const InputOrigin& origin) {
  const std::uint64_t lost = stream(s).sequence.observe(origin.publisher, origin.seq);
  switch (s) {
    case InputStream::kTorque: counters_.dropped_torque += lost; break;
    case InputStream::kPreload: counters_.dropped_preload += lost; break;
    case InputStream::kJointStates: counters_.dropped_motion += lost; break;
    case InputStream::kVibration: counters_.dropped_vibration += lost; break;
  }
}

InputOutcome InputGate::checkFrame(Stamp stamp, const InputOrigin& origin) {
  if (!isWrongFrame(origin.frame_id)) return InputOutcome::kAccepted;
  return reject(InputOutcome::kWrongFrame, InputStream::kTorque, stamp,
                "header.frame_id = '" + printableText(origin.frame_id) +
                    "', expected ~torque_frame = '" + torque_frame_ +
                    "' (the sign of torque.z selects the loaded flank)",
                origin.frame_id);
}

InputOutcome InputGate::checkStamp(InputStream s, Stamp stamp) const {
  if (isZeroStamp(stamp)) return InputOutcome::kZeroStamp;
  if (outsideRosTime(stamp)) return InputOutcome::kStampRange;
  if (isOutOfOrder(stamp, stream(s).last)) return InputOutcome::kOutOfOrder;
  return InputOutcome::kAccepted;
}

std::optional<std::string> InputGate::noteSourceRestart(InputStream s, Stamp stamp) {
  const std::optional<Stamp> last = stream(s).last;
  if (!sourceRestarted(stamp, last)) return std::nullopt;
  ++counters_.stamp_resets;
  stamps_restarted_ = true;
  return std::string(toString(s)) + " stamp went back by " +
         formatValue(secondsBetween(*last, stamp)) +
         " s (more than ~stamp_jump_back): source restarted";
}

std::optional<std::string> InputGate::observeClock(Stamp now) {
  // A looping bag's first messages can arrive before its /clock jump (separate connections, and
  // /clock lags by up to its period): if the stamps already restarted since the last jump, that
  // jump is the same restart; it is not reset a second time.
  bool back = clockJumpedBack(now);
  if (back && stamps_restarted_) {
    stamps_restarted_ = false;
    back = false;
  }
  std::optional<std::string> reason;
  if (back) {
    ++counters_.clock_resets;
    reason = "clock went back from " + formatValue(last_clock_->toSec()) + " s to " +
             formatValue(now.toSec()) + " s";
  }
  last_clock_ = now;
  return reason;
}

InputOutcome InputGate::reject(InputOutcome why, InputStream s, Stamp stamp,
                               const std::string& reason, std::string_view found) {
  switch (s) {
    case InputStream::kTorque: ++counters_.rejected_torque; break;
    case InputStream::kPreload: ++counters_.rejected_preload; break;
    case InputStream::kJointStates: ++counters_.rejected_motion; break;
    case InputStream::kVibration: ++counters_.rejected_vibration; break;
  }
  refusals_.record(s, why, stamp, reason, found);
  switch (why) {
    case InputOutcome::kZeroStamp: ++counters_.zero_stamps; break;
    case InputOutcome::kOutOfOrder: ++counters_.out_of_order; break;
    case InputOutcome::kInvalidValue: ++counters_.invalid_values; break;
    case InputOutcome::kUnreachableLoad: ++counters_.unreachable_loads; break;
    case InputOutcome::kWrongFrame: ++counters_.wrong_frames; break;
    case InputOutcome::kStampRange: ++counters_.stamps_out_of_range; break;
    case InputOutcome::kAccepted: break;
  }
  events_.record(std::string(toString(s)) + " rejected (" + toString(why) + "): " + reason);
  return why;
}

void InputGate::accept(InputStream s, Stamp stamp) {
  switch (s) {
    case InputStream::kTorque: ++counters_.accepted_torque; break;
    case InputStream::kPreload: ++counters_.accepted_preload; break;
    case InputStream::kJointStates: ++counters_.accepted_motion; break;
    case InputStream::kVibration: ++counters_.accepted_vibration; break;
  }
  stream(s).last = stamp;
}

void InputGate::forgetStamps() {
  for (Stream& s : streams_) s.last.reset();
}

std::size_t InputGate::unnumberedPublishers() const {
  std::size_t n = 0;
  for (const Stream& s : streams_) n += s.sequence.unnumberedPublishers();
  return n;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

const char* toString(InputStream stream) {
  switch (stream) {
    case InputStream::kTorque: return "torque";
    case InputStream::kPreload: return "preload";
    case InputStream::kJointStates: return "joint_states";
    case InputStream::kVibration: return "vibration";
  }
  return "?";
}

void RefusalTally::record(InputStream stream, InputOutcome why, Stamp stamp,
                          std::string_view reason, std::string_view found) {
  Entry& e = entries_[static_cast<std::size_t>(stream)][static_cast<std::size_t>(why)];
  if (e.count++ == 0) {
    e.first_stamp = stamp;
    e.first_reason = printableText(reason);
  }
  if (found.empty()) return;
  // Compared as stored (printable): the values come from messages, whatever bytes they hold.
  const std::string value = printableText(found);
  for (Found& f : e.found) {
    if (f.value == value) {
      ++f.count;
      return;
    }
  }
  if (e.found.size() < kMaxFound) {
    e.found.push_back({value, 1});
  } else {
    ++e.found_other;
  }
}

const RefusalTally::Entry& RefusalTally::entry(InputStream stream, InputOutcome why) const {
  return entries_[static_cast<std::size_t>(stream)][static_cast<std::size_t>(why)];
}

std::uint64_t RefusalTally::total(InputStream stream) const {
  std::uint64_t n = 0;
  for (const Entry& e : entries_[static_cast<std::size_t>(stream)]) n += e.count;
  return n;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/pipeline/stage_counters.hpp"

#include <atomic>
#include <utility>

namespace drivetrain_stiffness {

void EventLog::record(std::string text) {
  // One sequence for every EventLog: the merge takes the event with the largest order as the last.
  static std::atomic<std::uint64_t> sequence{0};
  text_ = std::move(text);
  order_ = ++sequence;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/pipeline/sequence_gaps.hpp"

#include <algorithm>

namespace drivetrain_stiffness {

std::uint64_t SequenceGaps::observe(std::string_view publisher, std::uint32_t seq) {
  auto it = std::find_if(publishers_.begin(), publishers_.end(),
                         [&](const Publisher& p) { return p.name == publisher; });
  if (it == publishers_.end()) {
    if (publishers_.size() >= kMaxPublishers) {
      ++untracked_;
      return 0;
    }
    publishers_.push_back({std::string(publisher), seq, false});
    return 0;
  }
  // Unsigned difference: wraps with the numbers (2^32 messages are 5 days at 10 kHz).
  const std::uint32_t ahead = seq - it->last;
  it->last = seq;
  if (ahead == 0) return 0;
  it->advanced = true;
  if (ahead >= (1u << 31)) {
    ++renumberings_;
    return 0;
  }
  return ahead - 1;
}

std::size_t SequenceGaps::unnumberedPublishers() const {
  return static_cast<std::size_t>(std::count_if(publishers_.begin(), publishers_.end(),
                                                [](const Publisher& p) { return !p.advanced; }));
}

}  // namespace drivetrain_stiffness

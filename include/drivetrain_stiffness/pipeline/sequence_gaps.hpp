// Messages lost on the way, from the gaps in each publisher's header.seq: docs/reliability.md
// "Overload".
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace drivetrain_stiffness {

class SequenceGaps {
 public:
  /// Publishers tracked per stream; further ones count as untracked.
  static constexpr std::size_t kMaxPublishers = 64;

  /// The messages `publisher` numbered since its previous one that never arrived: seq - last - 1
  /// when seq is 1 to 2^31 - 1 ahead (uint32, wrapping), else 0 (seq = last: unnumbered; further:
  /// a renumbering, counted in renumberings()).
  std::uint64_t observe(std::string_view publisher, std::uint32_t seq);

  std::uint64_t untracked() const { return untracked_; }
  std::uint64_t renumberings() const { return renumberings_; }
  /// Publishers whose numbers never advanced (their drops cannot be seen).
  std::size_t unnumberedPublishers() const;

 private:
  struct Publisher {
    std::string name;
    std::uint32_t last = 0;
    bool advanced = false;
  };
  std::vector<Publisher> publishers_;
  std::uint64_t untracked_ = 0, renumberings_ = 0;
};

}  // namespace drivetrain_stiffness

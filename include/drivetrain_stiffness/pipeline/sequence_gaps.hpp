// Messages lost on the way: a publisher that numbers its messages (std_msgs/Header.seq) shows every
// message dropped between its publish() and our callback (its own outgoing queue, the transport,
// roscpp's subscriber queue, rosbag record's queue) as a gap in the numbers that do arrive. roscpp
// and rospy number every message of a type with a header themselves, per publication (roscpp's
// Publication::enqueueMessage writes its counter into the serialized header when the advertised
// type has one); rosbag play sends the recorded numbers unchanged (it advertises without a header
// type), so a recording's own losses show too. Only a nodelet's zero-copy (intra-process)
// publication carries whatever the publisher wrote. One table per input stream, keyed by publisher
// (the caller id). Allocates only for a publisher not seen before, and never beyond kMaxPublishers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace drivetrain_stiffness {

class SequenceGaps {
 public:
  /// Publishers tracked per stream; messages from further ones are counted as untracked.
  static constexpr std::size_t kMaxPublishers = 64;

  /// The number of messages `publisher` numbered between its previous message and this one that
  /// never arrived (0 for its first message). Rules, on uint32 numbers that wrap:
  ///  - seq = last + 1: none lost;
  ///  - seq = last: the publisher does not number its messages (seq stays 0): none can be seen;
  ///  - last + 1 < seq, less than 2^31 ahead: seq - last - 1 lost;
  ///  - seq behind last (2^31 or more ahead): the publisher restarted its numbering (a new
  ///    process under the same name, a looping bag): none counted, counted as a renumbering.
  std::uint64_t observe(std::string_view publisher, std::uint32_t seq);

  std::uint64_t untracked() const { return untracked_; }
  std::uint64_t renumberings() const { return renumberings_; }
  /// Publishers seen whose numbers never advanced: drops from them cannot be detected.
  std::size_t unnumberedPublishers() const;

 private:
  struct Publisher {
    std::string name;
    std::uint32_t last = 0;
    bool advanced = false;  ///< its numbers moved at least once
  };
  std::vector<Publisher> publishers_;
  std::uint64_t untracked_ = 0, renumberings_ = 0;
};

}  // namespace drivetrain_stiffness

// checkBagIndex: what a closed bag's index promises, checked against the file before rosbag::Bag
// reads it. librosbag trusts the file: it parses record headers out of a chunk's buffer at the
// offsets the index gives without bounds checks (Bag::readHeaderFromBuffer), allocates what a
// size field asks for, and roscpp_serialization resizes arrays before it checks the bytes are
// there; one damaged byte in a chunk or its index is a SIGSEGV or a memory bomb inside librosbag.
// So drivetrain_replay hands a bag to rosbag::View only after this check walked the same records
// rosbag reads (Bag::startReadingVersion200: the bag header, every chunk header and the index data
// records after it, the connection and chunk info records at index_pos) and every record and
// message the view will deserialize, and it stops the view before the first one that failed.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <ros/time.h>

#include "bag_sequential_reader.hpp"  // NOLINT(build/include_subdir)
#include "message_layout.hpp"         // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {

/// A topic of a bag: one connection, with its message count.
struct BagTopic {
  std::string topic, type, md5sum;
  std::uint64_t messages = 0;
};

/// How the replay reads a connection's messages.
struct ReadRule {
  bool read = false;  ///< the view visits them (a named topic)
  std::optional<MessageLayout>
      layout;  ///< and deserializes them as this type (its MD5 sum matches)
};
using ReadRules = std::function<ReadRule(const BagConnection&)>;

struct BagIndexCheck {
  /// The index is whole and agrees with the chunks: rosbag::Bag may open the bag and rosbag::View
  /// read it up to `stop`. Otherwise `index_damage` says why and the bag is read without its index.
  bool usable = false;
  std::optional<BagDamage> index_damage;
  /// The record time of the first message (in the view's time order) whose record or bytes are
  /// damaged, and where and what: the view stops before it.
  std::optional<ros::Time> stop;
  std::optional<BagDamage> damage;
  std::vector<BagTopic> topics;  ///< every connection, in id order, with the index's message count
};

/// Checks a bag of format 2.0. Throws InvalidInput naming the file if it cannot be read or is not
/// a bag of format 2.0; damage is reported, never thrown. Time and memory grow with the file: one
/// pass over it, one chunk in memory at a time.
BagIndexCheck checkBagIndex(const std::string& path, const ReadRules& rules);

}  // namespace drivetrain_stiffness

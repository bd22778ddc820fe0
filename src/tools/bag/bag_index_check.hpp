// A closed bag's index checked against the file before librosbag reads it:
// docs/replay_exit_codes.md "How a damaged bag is read".
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

/// One connection of a bag and its message count.
struct BagTopic {
  std::string topic, type, md5sum;
  std::uint64_t messages = 0;
};

/// How the replay reads a connection's messages.
struct ReadRule {
  bool read = false;                    ///< the view visits them
  std::optional<MessageLayout> layout;  ///< and deserializes them as this type
};
using ReadRules = std::function<ReadRule(const BagConnection&)>;

struct BagIndexCheck {
  bool usable = false;                    ///< rosbag::View may read the bag up to `stop`
  std::optional<BagDamage> index_damage;  ///< why not usable
  std::optional<ros::Time> stop;          ///< record time of the first damaged message
  std::optional<BagDamage> damage;        ///< where and what that damage is
  std::vector<BagTopic> topics;           ///< every connection, in id order
};

/// Checks a bag of format 2.0; damage is reported, never thrown. Throws InvalidInput naming the
/// file if it cannot be read or is not a bag of format 2.0.
BagIndexCheck checkBagIndex(const std::string& path, const ReadRules& rules);

}  // namespace drivetrain_stiffness

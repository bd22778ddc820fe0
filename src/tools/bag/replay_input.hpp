// drivetrain_replay's input: the torque, preload and joint_states messages of a recorded bag, each
// one read and deserialized before the message loop gets it, so the loop never meets a read error:
// the first message that cannot be read ends the input, and damage() says where (byte offset) and
// what.
//  - A closed bag whose index checkBagIndex finds whole is read with rosbag::View in record-time
//    order through the index, up to the first message whose record or bytes the check found
//    damaged (the index also lets the view read past damage in records it never visits, which
//    would stop a sequential reading). rosbag only ever reads what the check walked.
//  - Any other bag (no index: a recording cut short, a truncated copy; a damaged bag header or
//    index) is read by SequentialBagReader, in file order (the order rosbag record wrote it:
//    record-time order), up to the first damage.
// Every message is checked against its type's layout (message_layout.hpp) before it is
// deserialized.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <boost/shared_ptr.hpp>
#include <geometry_msgs/WrenchStamped.h>
#include <sensor_msgs/JointState.h>
#include <rosbag/view.h>

#include "bag_index_check.hpp"        // NOLINT(build/include_subdir)
#include "bag_sequential_reader.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/VibrationBlock.h"
#include "drivetrain_stiffness/pipeline/refusal_tally.hpp"

namespace drivetrain_stiffness {

/// A bag topic is the wanted one, with or without the leading '/'.
bool topicMatches(const std::string& topic, const std::string& wanted);

/// The bag topic of each input stream, indexed by InputStream.
using ReplayTopics = std::array<std::string, kInputStreams>;

/// One input message, used as the loop used rosbag::MessageInstance, but already read.
class ReplayMessage {
 public:
  const ros::Time& getTime() const { return time_; }  ///< record time
  const std::string& getTopic() const { return *topic_; }
  /// The recording's publisher (its connection's callerid; "" if the bag has none).
  const std::string& getCallerId() const { return *caller_id_; }
  /// The recorded type (its connection's "type", e.g. "geometry_msgs/WrenchStamped").
  const std::string& getDataType() const { return *data_type_; }
  /// geometry_msgs::WrenchStamped on the torque topic, drivetrain_stiffness::Preload on the preload
  /// topic, sensor_msgs::JointState on the joint_states topic; null if the recorded type is another
  /// (MD5 sum), as MessageInstance::instantiate.
  template <class T>
  boost::shared_ptr<T> instantiate() const;

 private:
  friend class ReplayInput;
  ros::Time time_;
  const std::string* topic_ =
      nullptr;  ///< the connection's, which outlives the message (no copy per message)
  const std::string* caller_id_ = nullptr;  ///< likewise
  const std::string* data_type_ = nullptr;  ///< likewise
  boost::shared_ptr<geometry_msgs::WrenchStamped> torque_;
  boost::shared_ptr<drivetrain_stiffness::Preload> preload_;
  boost::shared_ptr<sensor_msgs::JointState> joint_states_;
  boost::shared_ptr<drivetrain_stiffness::VibrationBlock> vibration_;
};

template <>
inline boost::shared_ptr<geometry_msgs::WrenchStamped> ReplayMessage::instantiate() const {
  return torque_;
}
template <>
inline boost::shared_ptr<drivetrain_stiffness::Preload> ReplayMessage::instantiate() const {
  return preload_;
}
template <>
inline boost::shared_ptr<sensor_msgs::JointState> ReplayMessage::instantiate() const {
  return joint_states_;
}
template <>
inline boost::shared_ptr<drivetrain_stiffness::VibrationBlock> ReplayMessage::instantiate() const {
  return vibration_;
}

class ReplayInput {
 public:
  /// Throws InvalidInput ("--bag = 'PATH': ...") if the path does not exist, is a directory or
  /// another non-file, cannot be read, is not a bag, or is a bag of a format other than 2.0.
  ReplayInput(const std::string& path, const ReplayTopics& topics);

  struct End {};
  class Iterator {
   public:
    explicit Iterator(ReplayInput& input) : input_(&input) {}
    const ReplayMessage& operator*() const { return input_->message_; }
    Iterator& operator++() {
      input_->advance();
      return *this;
    }
    bool operator!=(End) const { return input_->has_message_; }

   private:
    ReplayInput* input_;
  };
  Iterator begin();  ///< reads the first message (once)
  End end() const { return {}; }

  /// Why reading stopped before the end of the bag (offset and what); nullopt after the whole bag.
  const std::optional<BagDamage>& damage() const { return damage_; }
  /// Every topic of the bag with its type and message count: the index's, or without it those read
  /// so far (all of them once the input ended without damage).
  std::vector<BagTopic> topics() const;

 private:
  void advance();
  bool nextIndexed();
  bool nextSequential();
  /// The input stream `topic` feeds (torque first, as drivetrain_replay's loop), or none.
  std::optional<InputStream> streamOf(const std::string& topic) const;
  bool isWanted(const std::string& topic) const { return streamOf(topic).has_value(); }
  ReadRule readRule(const BagConnection& connection) const;
  void decode(const BagRecordMessage& raw, ReplayMessage& message) const;
  /// Sets `message`'s pointer of `stream`'s type to make(T*) and the others to null.
  template <class Make>
  static void fill(ReplayMessage& message, InputStream stream, const Make& make);
  BagDamage endOfSequentialReading() const;
  std::string withoutIndex() const;  ///< what a sequential reading's damage says of the index
  BagDamage locateDamage(const std::string& rosbag_error) const;

  std::string path_;
  ReplayTopics topics_;
  std::unique_ptr<rosbag::Bag> bag_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator view_next_, view_end_;
  std::unique_ptr<SequentialBagReader> sequential_;
  BagIndexCheck check_;
  std::string index_unusable_;  ///< why the bag is read without its index (sequential reading)
  ReplayMessage message_;
  bool begun_ = false, has_message_ = false;
  std::uint64_t read_ = 0;  ///< messages handed out
  std::optional<BagDamage> damage_;
};

}  // namespace drivetrain_stiffness

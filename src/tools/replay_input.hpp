// drivetrain_replay's input: the torque, preload and joint_states messages of a recorded bag, each one read and
// deserialized before the message loop gets it, so the loop never meets a read error: the first
// message that cannot be read ends the input, and damage() says where (byte offset) and what.
//  - A bag rosbag::Bag opens is read with rosbag::View in record-time order through its index, as
//    before (the index also lets rosbag read past damage that stops a sequential reading, such as a
//    damaged record length). When a message fails to read, SequentialBagReader locates the damage:
//    rosbag's errors name no offset.
//  - A bag rosbag::Bag cannot open (no index: a recording cut short, a truncated copy; a damaged
//    bag header or index) is read by SequentialBagReader, in file order (the order rosbag record
//    wrote it: record-time order), up to the first damage.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <boost/shared_ptr.hpp>
#include <geometry_msgs/WrenchStamped.h>
#include <sensor_msgs/JointState.h>
#include <rosbag/view.h>

#include "bag_sequential_reader.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/Preload.h"

namespace drivetrain_stiffness {

/// A bag topic is the wanted one, with or without the leading '/'.
bool topicMatches(const std::string& topic, const std::string& wanted);

/// One input message, used as the loop used rosbag::MessageInstance, but already read.
class ReplayMessage {
 public:
  const ros::Time& getTime() const { return time_; }  ///< record time
  const std::string& getTopic() const { return *topic_; }
  /// The recording's publisher (its connection's callerid; "" if the bag has none).
  const std::string& getCallerId() const { return *caller_id_; }
  /// geometry_msgs::WrenchStamped on the torque topic, drivetrain_stiffness::Preload on the preload
  /// topic, sensor_msgs::JointState on the joint_states topic; null if the recorded type is another
  /// (MD5 sum), as MessageInstance::instantiate.
  template <class T>
  boost::shared_ptr<T> instantiate() const;

 private:
  friend class ReplayInput;
  ros::Time time_;
  const std::string* topic_ = nullptr;  ///< the connection's, which outlives the message (no copy per message)
  const std::string* caller_id_ = nullptr;  ///< likewise
  boost::shared_ptr<geometry_msgs::WrenchStamped> torque_;
  boost::shared_ptr<drivetrain_stiffness::Preload> preload_;
  boost::shared_ptr<sensor_msgs::JointState> joint_states_;
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

class ReplayInput {
 public:
  /// Throws InvalidInput ("--bag = 'PATH': ...") if the file cannot be read, is not a bag, or is a
  /// bag rosbag cannot open in a format other than 2.0 (the only one read without the index).
  ReplayInput(const std::string& path, const std::string& torque_topic, const std::string& preload_topic,
              const std::string& joint_states_topic = "joint_states");

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

 private:
  void advance();
  bool nextIndexed();
  bool nextSequential();
  bool isTorque(const std::string& topic) const;
  bool isJointStates(const std::string& topic) const;
  bool isWanted(const std::string& topic) const;
  void decode(const BagRecordMessage& raw, ReplayMessage& message) const;
  BagDamage endOfSequentialReading() const;
  std::string withoutIndex() const;  ///< what a sequential reading's damage says of rosbag
  BagDamage locateDamage(const std::string& rosbag_error) const;

  std::string path_, torque_topic_, preload_topic_, joint_states_topic_;
  std::unique_ptr<rosbag::Bag> bag_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator view_next_, view_end_;
  std::unique_ptr<SequentialBagReader> sequential_;
  std::string rosbag_open_error_;  ///< why rosbag::Bag could not open the bag (sequential reading)
  ReplayMessage message_;
  bool begun_ = false, has_message_ = false;
  std::uint64_t read_ = 0;  ///< messages handed out
  std::optional<BagDamage> damage_;
};

}  // namespace drivetrain_stiffness

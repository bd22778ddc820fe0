#include "scenario_bag.hpp"  // NOLINT(build/include_subdir)

#include <cmath>
#include <cstdint>
#include <limits>

#include <geometry_msgs/WrenchStamped.h>
#include <rosbag/bag.h>
#include <sensor_msgs/JointState.h>

#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/VibrationBlock.h"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

ros::Time fromNanoseconds(std::int64_t ns) {
  return ros::Time(static_cast<std::uint32_t>(ns / 1000000000LL),
                   static_cast<std::uint32_t>(ns % 1000000000LL));
}

void requireName(const std::string& field, const std::string& value) {
  if (value.empty()) throw InvalidInput(field + " = '': must not be empty");
}

/// The vibration record's blocks, each written once its last sample's interval has ended: block
/// b holds samples [b n, (b + 1) n), is stamped at its first sample, and its header.seq is b.
class VibrationBlockWriter {
 public:
  VibrationBlockWriter(rosbag::Bag& bag, const std::string& topic, const VibrationRecord* record,
                       std::int64_t epoch_ns)
      : bag_(bag),
        topic_(topic),
        record_(record),
        epoch_ns_(epoch_ns),
        blocks_(record ? record->samples() / static_cast<std::size_t>(record->block) : 0) {}

  /// Writes every block recorded by `ns` [ns]; returns how many.
  std::uint64_t writeUntil(std::int64_t ns) {
    std::uint64_t written = 0;
    for (; next_ < blocks_; ++next_) {
      const std::size_t n = static_cast<std::size_t>(record_->block), first = next_ * n;
      const std::int64_t record_ns = sampleNs(first + n);
      if (record_ns > ns) break;
      drivetrain_stiffness::VibrationBlock v;
      v.header.seq = static_cast<std::uint32_t>(next_);
      v.header.stamp = fromNanoseconds(sampleNs(first));
      v.sample_rate = record_->rate;
      v.channels.assign(record_->channels.begin(), record_->channels.end());
      v.data.assign(record_->data.begin() + static_cast<std::ptrdiff_t>(2 * first),
                    record_->data.begin() + static_cast<std::ptrdiff_t>(2 * (first + n)));
      bag_.write(topic_, fromNanoseconds(record_ns), v);
      ++written;
    }
    return written;
  }

 private:
  std::int64_t sampleNs(std::size_t sample) const {
    return epoch_ns_ + std::llround(static_cast<double>(sample) * 1e9 / record_->rate);
  }

  rosbag::Bag& bag_;
  const std::string& topic_;
  const VibrationRecord* record_;
  std::int64_t epoch_ns_;
  std::size_t blocks_, next_ = 0;
};

void writeTorque(rosbag::Bag& bag, const std::string& topic, const RigEvent& e,
                 const ros::Time& record, const ros::Time& stamp, std::uint32_t& seq) {
  geometry_msgs::WrenchStamped w;
  seq += e.lost_before;
  w.header.seq = seq++;
  w.header.stamp = stamp;
  w.header.frame_id = e.frame_id;
  w.wrench.torque.z = *e.torque;
  bag.write(topic, record, w);
}

void writePreload(rosbag::Bag& bag, const std::string& topic, const RigEvent& e,
                  const ros::Time& record, const ros::Time& stamp, std::uint32_t& seq) {
  drivetrain_stiffness::Preload p;
  seq += e.lost_before;
  p.header.seq = seq++;
  p.header.stamp = stamp;
  for (const PreloadSetting& s : e.preload) {
    drivetrain_stiffness::BearingPreload b;
    b.name = s.name;
    b.axial_preload = s.axial_preload;
    b.radial_preload = s.radial_preload;
    b.inner_interference = s.inner_interference;
    b.outer_interference = s.outer_interference;
    p.bearings.push_back(b);
  }
  bag.write(topic, record, p);
}

/// sensor_msgs/JointState: one entry per shaft; velocity empty when not measured, effort empty
/// (the torque has its own topic). frame_id empty: the angles are about each shaft's own axis.
void writeJointState(rosbag::Bag& bag, const ScenarioBagOptions& o, const RigEvent& e,
                     const ros::Time& record, const ros::Time& stamp, std::uint32_t& seq) {
  sensor_msgs::JointState j;
  seq += e.lost_before;
  j.header.seq = seq++;
  j.header.stamp = stamp;
  j.name.push_back(o.pinion_joint);
  j.position.push_back(e.motion->pinion_angle);
  if (e.motion->gear_angle) {
    j.name.push_back(o.gear_joint);
    j.position.push_back(*e.motion->gear_angle);
  }
  if (e.motion->pinion_velocity) {
    j.velocity.push_back(*e.motion->pinion_velocity);
    if (e.motion->gear_angle) {
      // JointState's arrays are all as long as name, or empty.
      if (!e.gear_velocity)
        throw InvalidInput("event at t = " + formatValue(e.t) +
                           ": a pinion velocity without gear_velocity");
      j.velocity.push_back(*e.gear_velocity);
    }
  }
  bag.write(o.joint_topic, record, j);
}

}  // namespace

ScenarioBagCounts writeScenarioBag(const std::vector<RigEvent>& events, const ScenarioBagOptions& o,
                                   const std::string& path, const VibrationRecord* vibration) {
  if (!(o.epoch >= 1.0 && o.epoch < 4e9))
    throw InvalidInput("epoch = " + formatValue(o.epoch) + ": must be in [1, 4e9) s");
  requireName("torque_topic", o.torque_topic);
  requireName("preload_topic", o.preload_topic);
  requireName("joint_topic", o.joint_topic);
  requireName("pinion_joint", o.pinion_joint);
  requireName("gear_joint", o.gear_joint);
  if (vibration) requireName("vibration_topic", o.vibration_topic);
  const std::int64_t epoch_ns = std::llround(o.epoch * 1e9);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  ScenarioBagCounts counts;
  // header.seq numbers each stream from 0, as roscpp and rospy do; a gap is a message lost on the
  // way.
  std::uint32_t seq = 0, preload_seq = 0, joint_seq = 0;
  VibrationBlockWriter blocks(bag, o.vibration_topic, vibration, epoch_ns);
  for (const RigEvent& e : events) {
    const std::int64_t ns =
        epoch_ns + std::llround(e.t * 1e9);         // record time: when the rig sent it
    counts.vibration += blocks.writeUntil(ns - 1);  // blocks completed before this record time
    const ros::Time record = fromNanoseconds(ns);
    const ros::Time stamp =
        e.zero_stamp ? ros::Time(0, 0) : fromNanoseconds(ns + std::llround(e.stamp_offset * 1e9));
    if (e.torque) {
      writeTorque(bag, o.torque_topic, e, record, stamp, seq);
      ++counts.torque;
    }
    if (!e.preload.empty()) {
      writePreload(bag, o.preload_topic, e, record, stamp, preload_seq);
      ++counts.preload;
    }
    if (e.motion) {
      writeJointState(bag, o, e, record, stamp, joint_seq);
      ++counts.joint_states;
    }
  }
  counts.vibration += blocks.writeUntil(std::numeric_limits<std::int64_t>::max());
  bag.close();
  return counts;
}

}  // namespace drivetrain_stiffness

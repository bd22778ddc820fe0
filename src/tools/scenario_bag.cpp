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
  // Vibration block b: samples [b n, (b + 1) n), stamped at its first sample, recorded when its
  // last sample's interval ends; header.seq is b.
  const std::size_t blocks =
      vibration ? vibration->samples() / static_cast<std::size_t>(vibration->block) : 0;
  std::size_t next_block = 0;
  auto blockNs = [&](std::size_t sample) {
    return epoch_ns + std::llround(static_cast<double>(sample) * 1e9 / vibration->rate);
  };
  auto writeBlocksUntil = [&](std::int64_t ns) {
    for (; next_block < blocks; ++next_block) {
      const std::size_t n = static_cast<std::size_t>(vibration->block), first = next_block * n;
      const std::int64_t record_ns = blockNs(first + n);
      if (record_ns > ns) return;
      drivetrain_stiffness::VibrationBlock v;
      v.header.seq = static_cast<std::uint32_t>(next_block);
      v.header.stamp = fromNanoseconds(blockNs(first));
      v.sample_rate = vibration->rate;
      v.channels.assign(vibration->channels.begin(), vibration->channels.end());
      v.data.assign(vibration->data.begin() + static_cast<std::ptrdiff_t>(2 * first),
                    vibration->data.begin() + static_cast<std::ptrdiff_t>(2 * (first + n)));
      bag.write(o.vibration_topic, fromNanoseconds(record_ns), v);
      ++counts.vibration;
    }
  };
  for (const RigEvent& e : events) {
    const std::int64_t ns =
        epoch_ns + std::llround(e.t * 1e9);  // record time: when the rig sent it
    writeBlocksUntil(ns - 1);                // a block completed before this event's record time
    const ros::Time record = fromNanoseconds(ns);
    const ros::Time stamp =
        e.zero_stamp ? ros::Time(0, 0) : fromNanoseconds(ns + std::llround(e.stamp_offset * 1e9));
    if (e.torque) {
      geometry_msgs::WrenchStamped w;
      seq += e.lost_before;
      w.header.seq = seq++;
      w.header.stamp = stamp;
      w.header.frame_id = e.frame_id;
      w.wrench.torque.z = *e.torque;
      bag.write(o.torque_topic, record, w);
      ++counts.torque;
    }
    if (!e.preload.empty()) {
      drivetrain_stiffness::Preload p;
      preload_seq += e.lost_before;
      p.header.seq = preload_seq++;
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
      bag.write(o.preload_topic, record, p);
      ++counts.preload;
    }
    if (e.motion) {
      // sensor_msgs/JointState: one entry per shaft; velocity empty when not measured, effort empty
      // (the torque has its own topic). frame_id empty: the angles are about each shaft's own axis.
      sensor_msgs::JointState j;
      joint_seq += e.lost_before;
      j.header.seq = joint_seq++;
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
      ++counts.joint_states;
    }
  }
  writeBlocksUntil(std::numeric_limits<std::int64_t>::max());
  bag.close();
  return counts;
}

}  // namespace drivetrain_stiffness

// The rig's measured motion: one encoder reading of both shafts (sensor_msgs/JointState on the
// ROS side, converted at the edge). ROS-free.
//
// Sign convention (REP 103, docs/ros_api.md "joint_states"): each angle follows the right-hand rule
// about its own shaft's axis, and both axes point along the rig frame's z. The gears turn in
// opposite senses, so the gear angle falls when the pinion's rises: theta_g = -(z_p / z_g) theta_p
// plus a constant and the transmission error.
#pragma once

#include <optional>

namespace drivetrain_stiffness {

struct MotionInput {
  double pinion_angle =
      0.0;  ///< [rad] (wrapped or not: only its changes and the mesh phase are used)
  std::optional<double> pinion_velocity;  ///< [rad/s]; absent: differentiated from the angle
  std::optional<double> gear_angle;       ///< [rad]; absent: no ratio (slip) check
};

}  // namespace drivetrain_stiffness

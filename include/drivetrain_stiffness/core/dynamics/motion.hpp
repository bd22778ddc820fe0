// One encoder reading of both shafts; sign convention in docs/ros_api.md "joint_states".
#pragma once

#include <optional>

namespace drivetrain_stiffness {

struct MotionInput {
  double pinion_angle = 0.0;              ///< [rad], wrapped or not
  std::optional<double> pinion_velocity;  ///< [rad/s]; absent: differentiated
  std::optional<double> gear_angle;       ///< [rad]; absent: no ratio check
};

}  // namespace drivetrain_stiffness

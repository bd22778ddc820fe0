// The rig's two shaft encoders as drivetrain_rig_sim writes them (joint_states): each angle
// quantised to a 2^20-count-per-revolution encoder's grid, the gear's from the kinematic ratio
// with the sign convention of core/motion.hpp. ROS-free.
#pragma once

#include <optional>

#include "drivetrain_stiffness/core/motion.hpp"
#include "drivetrain_stiffness/core/speed_profile.hpp"

namespace drivetrain_stiffness {

constexpr double kEncoderCounts = 1048576.0;  ///< 2^20 counts per revolution (a 20-bit encoder)

/// The encoder's reading of `angle` [rad]: round(theta 2^20 / (2 pi)) 2 pi / 2^20, an exact
/// multiple of the count 2 pi / 2^20 = 5.99e-6 rad, within half a count of the angle.
double quantiseEncoderAngle(double angle);

struct EncoderSample {
  MotionInput motion;  ///< quantised pinion and gear angles; the pinion's exact speed
  std::optional<double>
      gear_velocity;  ///< [rad/s] -(z_p / z_g) omega_p, beside motion.pinion_velocity
};

/// Both encoders at time t [s] with the pinion on `pinion`: theta_p quantised; theta_g =
/// -(z_p / z_g) theta_p (rigid kinematics, motion.hpp's sign convention: both axes along the rig
/// frame's z, so the gear turns the other way) quantised on its own; velocities (exact, not
/// quantised) only if `with_velocity`. ratio = z_p / z_g > 0.
EncoderSample readEncoders(const SpeedProfile& pinion, double t, double ratio, bool with_velocity);

}  // namespace drivetrain_stiffness

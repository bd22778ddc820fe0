// The rig's two shaft encoders as drivetrain_rig_sim writes them (joint_states).
#pragma once

#include <optional>

#include "drivetrain_stiffness/core/dynamics/motion.hpp"
#include "drivetrain_stiffness/core/dynamics/speed_profile.hpp"

namespace drivetrain_stiffness {

constexpr double kEncoderCounts = 1048576.0;  ///< 2^20 counts per revolution (a 20-bit encoder)

/// `angle` [rad] rounded to the nearest count 2 pi / 2^20.
double quantiseEncoderAngle(double angle);

struct EncoderSample {
  MotionInput motion;                   ///< quantised angles, the exact pinion speed
  std::optional<double> gear_velocity;  ///< [rad/s] -(z_p / z_g) omega_p
};

/// Both encoders at t [s]: theta_p and theta_g = -ratio theta_p (ratio = z_p / z_g > 0) quantised,
/// exact velocities only if `with_velocity`.
EncoderSample readEncoders(const SpeedProfile& pinion, double t, double ratio, bool with_velocity);

}  // namespace drivetrain_stiffness

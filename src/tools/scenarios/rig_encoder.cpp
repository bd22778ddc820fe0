#include "rig_encoder.hpp"  // NOLINT(build/include_subdir)

#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {

double quantiseEncoderAngle(double angle) {
  // Counts = round(theta N / (2 pi)), N = 2^20 counts per revolution; reading = counts 2 pi / N
  // (dividing by N, a power of two, is exact). + 0.0: a count of zero reads +0, never -0.
  return std::round(angle * kEncoderCounts / kTwoPi) * kTwoPi / kEncoderCounts + 0.0;
}

EncoderSample readEncoders(const SpeedProfile& pinion, double t, double ratio, bool with_velocity) {
  EncoderSample s;
  const double theta_p = pinion.angle(t);
  s.motion.pinion_angle = quantiseEncoderAngle(theta_p);
  // Meshing gears: r_p theta_p = -r_g theta_g at the pitch point with both angles about +z, and
  // r_p / r_g = z_p / z_g (equal modules), so theta_g = -(z_p / z_g) theta_p (motion.hpp).
  s.motion.gear_angle = quantiseEncoderAngle(-ratio * theta_p);
  if (with_velocity) {
    const double omega_p = pinion.speed(t);
    s.motion.pinion_velocity = omega_p;
    s.gear_velocity = -ratio * omega_p;
  }
  return s;
}

}  // namespace drivetrain_stiffness

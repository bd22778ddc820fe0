#include "drivetrain_stiffness/core/gear_geometry.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

void validateGearPair(const GearPairSpec& spec) {
  requirePositive("gears.module", spec.module);
  requireInOpenRange("gears.pressure_angle_deg", spec.pressure_angle * 180.0 / M_PI, 0.0, 45.0);
  for (int i = 0; i < 2; ++i) {
    if (spec.teeth[i] < 5) throwInvalid("gears.teeth[" + std::to_string(i) + "]", spec.teeth[i], "must be >= 5");
  }
}

double baseRadius(const GearPairSpec& spec, int gear_index) {
  if (gear_index != 0 && gear_index != 1) throwInvalid("gear_index", gear_index, "must be 0 (pinion) or 1 (gear)");
  return 0.5 * spec.module * spec.teeth[gear_index] * std::cos(spec.pressure_angle);
}

double meshForce(const GearPairSpec& spec, int gear_index, double torque) {
  requireFinite("torque", torque);
  return torque / baseRadius(spec, gear_index);
}

}  // namespace drivetrain_stiffness

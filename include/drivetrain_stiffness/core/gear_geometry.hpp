// Spur gear pair geometry needed by the bearing side: base radii for the mesh force.
// (The full involute geometry, contact ratio and mesh stiffness belong to issue 3's mesh module.)
#pragma once

#include <array>

namespace drivetrain_stiffness {

struct GearPairSpec {
  double module = 0.0;                    ///< m [m]
  double pressure_angle = 0.0;            ///< alpha [rad]
  std::array<int, 2> teeth{{0, 0}};       ///< z_pinion, z_gear
};

/// Validates the spec (module > 0, 0 < alpha < 45 deg, teeth >= 5); throws InvalidInput naming the field.
void validateGearPair(const GearPairSpec& spec);
/// Base radius r_b = m z cos(alpha) / 2 (ISO 21771:2007, d_b = d cos(alpha_t), d = m z) [m].
double baseRadius(const GearPairSpec& spec, int gear_index);
/// Normal mesh force along the line of action from a torque on gear `gear_index`: F = T / r_b
/// (seed 000 eq 14 and Table 1, F_m = T_p / r_p) [N]; sign follows the torque.
double meshForce(const GearPairSpec& spec, int gear_index, double torque);

}  // namespace drivetrain_stiffness

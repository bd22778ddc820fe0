// Gear pairs shared by the gear tests. The seed pair is seed 000 Table 1.
#pragma once

#include <cmath>

#include "drivetrain_stiffness/core/gear/gear_geometry.hpp"

namespace drivetrain_stiffness {
namespace test {

inline GearPairSpec seedPair() {
  GearPairSpec g;
  g.module = 0.6e-3;                     // seed 000 Table 1: m = 0.6 mm
  g.pressure_angle = 20.0 * M_PI / 180;  // 20 deg
  g.teeth = {20, 40};                    // z = 20 / 40
  g.face_width = 6.5e-3;                 // effective face width 6.5 mm
  g.material = {2.1e11, 0.3};            // E = 2.1e5 N/mm^2, nu = 0.3
  return g;
}

}  // namespace test
}  // namespace drivetrain_stiffness

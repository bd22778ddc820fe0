// Bearing specs shared by the core tests. The 7013 AC data are seed 003 Table 1; the others are
// synthetic geometries chosen to isolate one effect (zero clearance, many balls, ...).
#pragma once

#include <cmath>

#include "drivetrain_stiffness/core/bearing/ball_bearing.hpp"

namespace drivetrain_stiffness {
namespace test {

inline BallBearingSpec acbb7013() {
  BallBearingSpec s;
  s.type = BearingType::kAngularContact;
  s.balls = 19;                       // seed 003 Table 1
  s.ball_diameter = 11.1e-3;          // seed 003 Table 1
  s.pitch_diameter = 82.5e-3;         // d_i + D = 71.4 + 11.1 mm (seed 003 Table 1)
  s.inner_groove_conformity = 0.515;  // r_i = 5.7165 mm / 11.1 mm
  s.outer_groove_conformity = 0.515;
  s.contact_angle = 25.0 * M_PI / 180.0;
  s.width = 18e-3;
  s.material = {207e9, 0.29};  // seed 003 section 3
  FitGeometry g;
  g.bore_diameter = 65e-3;
  g.outside_diameter = 100e-3;
  g.inner_raceway_diameter = 71.4e-3;
  g.outer_raceway_diameter = 93.6e-3;
  g.shaft = g.housing = s.material;
  s.fit = g;
  return s;
}

inline BallBearingSpec deepGroove(int balls, double clearance) {
  BallBearingSpec s;
  s.type = BearingType::kDeepGroove;
  s.balls = balls;
  s.ball_diameter = 5e-3;
  s.pitch_diameter = 100e-3;
  s.inner_groove_conformity = 0.52;
  s.outer_groove_conformity = 0.53;
  s.diametral_clearance = clearance;
  s.material = {207e9, 0.3};
  return s;
}

}  // namespace test
}  // namespace drivetrain_stiffness

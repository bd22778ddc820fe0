#include "drivetrain_stiffness/config/json_report.hpp"

#include <cmath>

namespace drivetrain_stiffness {
namespace {
constexpr double kRadToDeg = 180.0 / M_PI;

nlohmann::json contactJson(const HertzPointContact& c) {
  return {{"rx", c.rx()},
          {"ry", c.ry()},
          {"curvature_sum_radius", c.curvatureSumRadius()},
          {"curvature_difference", c.curvatureDifference()},
          {"ellipticity", c.ellipticity().ellipticity},
          {"elliptic_integral_first", c.ellipticity().elliptic_first},
          {"elliptic_integral_second", c.ellipticity().elliptic_second},
          {"load_deflection_constant", c.loadDeflectionConstant()}};
}
}  // namespace

nlohmann::json bearingModelJson(const BearingSupport& support) {
  const BallBearing& b = support.bearing();
  return {{"type", toString(b.spec().type)},
          {"arrangement", toString(support.arrangement())},
          {"tilt", toString(support.tiltCondition())},
          {"balls", b.spec().balls},
          {"ellipticity_method", toString(b.spec().ellipticity)},
          {"groove_centre_distance", b.grooveCentreDistance()},
          {"unmounted_clearance", b.unmountedClearance()},
          {"inner_raceway_growth", b.innerRacewayGrowth()},
          {"outer_raceway_shrink", b.outerRacewayShrink()},
          {"mounted_clearance", b.mountedClearance()},
          {"free_contact_angle_deg", b.freeContactAngle() * kRadToDeg},
          {"inner_groove_centre_radius", b.innerGrooveCentreRadius()},
          {"load_deflection_constant", b.loadDeflectionConstant()},
          {"axial_preload", support.axialPreload()},
          {"preload_offset", support.preloadOffset()},
          {"inner_contact", contactJson(b.innerContact())},
          {"outer_contact", contactJson(b.outerContact())}};
}

nlohmann::json bearingSolutionJson(const BearingSupport& support, const BearingSolution& sol,
                                   const nlohmann::json& radial_secant) {
  nlohmann::json angles = nlohmann::json::array(), loads = nlohmann::json::array(),
                 lost = nlohmann::json::array(), pressures = nlohmann::json::array();
  int index = 0;
  for (const auto& row : sol.rows) {
    for (const BallState& ball : row) {
      angles.push_back(ball.contact_angle * kRadToDeg);
      loads.push_back(ball.load);
      pressures.push_back(ball.max_pressure);
      if (!ball.in_contact) lost.push_back(index);
      ++index;
    }
  }
  nlohmann::json matrix = nlohmann::json::array();
  for (int i = 0; i < 5; ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (int j = 0; j < 5; ++j) row.push_back(sol.stiffness(i, j));
    matrix.push_back(row);
  }
  const Vector5d& q = sol.displacement;
  return {{"model", bearingModelJson(support)},
          {"load", {{"force_x", sol.load[kUx]}, {"force_y", sol.load[kUy]}, {"force_z", sol.load[kUz]},
                    {"moment_x", sol.load[kThetaX]}, {"moment_y", sol.load[kThetaY]}}},
          {"displacement", {{"axial", q[kUz]}, {"radial", std::hypot(q[kUx], q[kUy])},
                            {"tilt", std::hypot(q[kThetaX], q[kThetaY])},
                            {"vector", {q[0], q[1], q[2], q[3], q[4]}},
                            {"datum", "concentric, axially centred rings"}}},
          {"rows", support.rows()},
          {"contact_angles_deg", angles},
          {"ball_loads", loads},
          {"ball_max_contact_pressure", pressures},
          {"balls_in_contact", sol.balls_in_contact},
          {"balls_out_of_contact", lost},
          {"max_contact_pressure", sol.max_contact_pressure},
          {"stiffness", {{"radial", sol.radialStiffness()},
                         {"radial_secant", radial_secant},
                         {"axial", sol.axialStiffness()},
                         {"tilt", sol.tiltStiffness()},
                         {"matrix", matrix},
                         {"kind", "radial, axial, tilt and matrix are tangent (dF/dq at the solved state); "
                                  "radial_secant is F_r / (u_r(F_r) - u_r(0))"},
                         {"dofs", {"u_x [m]", "u_y [m]", "u_z [m]", "theta_x [rad]", "theta_y [rad]"}}}},
          {"converged", sol.converged},
          {"iterations", sol.iterations},
          {"residual", sol.residual}};
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/config/json_report.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {
namespace {
constexpr double kRadToDeg = 180.0 / kPi;

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
          {"load",
           {{"force_x", sol.load[kUx]},
            {"force_y", sol.load[kUy]},
            {"force_z", sol.load[kUz]},
            {"moment_x", sol.load[kThetaX]},
            {"moment_y", sol.load[kThetaY]}}},
          {"displacement",
           {{"axial", q[kUz]},
            {"radial", std::hypot(q[kUx], q[kUy])},
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
          {"stiffness",
           {{"radial", sol.radialStiffness()},
            {"radial_secant", radial_secant},
            {"axial", sol.axialStiffness()},
            {"tilt", sol.tiltStiffness()},
            {"matrix", matrix},
            {"kind",
             "radial, axial, tilt and matrix are tangent (dF/dq at the solved state); "
             "radial_secant is F_r / (u_r(F_r) - u_r(0))"},
            {"dofs", {"u_x [m]", "u_y [m]", "u_z [m]", "theta_x [rad]", "theta_y [rad]"}}}},
          {"converged", sol.converged},
          {"iterations", sol.iterations},
          {"residual", sol.residual}};
}

nlohmann::json gearGeometryJson(const SpurGearGeometry& g) {
  auto pair = [&](double (SpurGearGeometry::*f)(int) const) {
    return nlohmann::json{(g.*f)(0), (g.*f)(1)};
  };
  return {
      {"reference_radius", pair(&SpurGearGeometry::referenceRadius)},
      {"base_radius", pair(&SpurGearGeometry::baseRadius)},
      {"tip_radius", pair(&SpurGearGeometry::tipRadius)},
      {"root_radius", pair(&SpurGearGeometry::rootRadius)},
      {"operating_pitch_radius", pair(&SpurGearGeometry::operatingPitchRadius)},
      {"operating_tooth_thickness", pair(&SpurGearGeometry::operatingToothThickness)},
      {"center_distance", g.centerDistance()},
      {"operating_pressure_angle_deg", g.operatingPressureAngle() * kRadToDeg},
      {"tip_shortening", g.tipShortening()},
      {"base_pitch", g.basePitch()},
      {"contact_ratio", g.contactRatio()},
      {"path_of_contact",
       {{"start", g.pathStart()},
        {"end", g.pathEnd()},
        {"pitch_point", g.pitchPoint()},
        {"length", g.pathEnd() - g.pathStart()},
        {"line_of_action", g.lineOfActionLength()},
        {"datum", "distance along the line of action from the pinion base-circle tangent point"}}},
      {"backlash", g.backlash()},
      {"back_flank_phase_offset", g.backFlankPhaseOffset()}};
}

nlohmann::json meshJson(const AntiBacklashMesh& mesh, int phases, double mesh_force) {
  nlohmann::json rows = nlohmann::json::array();
  double sum1 = 0, sum2 = 0, sums = 0, min1 = INFINITY, max1 = 0, mins = INFINITY, maxs = 0,
         min2 = INFINITY, max2 = 0;
  for (int i = 0; i < phases; ++i) {
    const double phi = static_cast<double>(i) / phases;
    const CompositeMesh c = mesh.at(phi, mesh_force);
    rows.push_back({{"phase", phi},
                    {"k1", c.k1},
                    {"k2", c.k2},
                    {"k_chain", c.k_chain},
                    {"ks", c.composite},
                    {"drive_pairs", c.drive_pairs},
                    {"back_pairs", c.back_pairs},
                    {"flanks", toString(c.contact)}});
    sum1 += c.k1;
    sum2 += c.k2;
    sums += c.composite;
    min1 = std::min(min1, c.k1);
    max1 = std::max(max1, c.k1);
    min2 = std::min(min2, c.k2);
    max2 = std::max(max2, c.k2);
    mins = std::min(mins, c.composite);
    maxs = std::max(maxs, c.composite);
  }
  const Iso6336Stiffness iso = iso6336Stiffness(mesh.geometry().spec());
  const CompositeMesh mean_state = mesh.at(0.0, mesh_force);
  nlohmann::json anti = {
      {"spring_stiffness", mesh.spec().spring_stiffness},
      {"preload_torque", mesh.spec().preload_torque},
      {"preload_force", mesh.preloadForce()},
      {"criterion", "both flanks loaded while -F_p (1 + k_c/k1) <= F_m <= F_p (1 + k1/k_c)"}};
  if (mean_state.k_chain > 0.0) {
    const double k1 = sum1 / phases, kc = mesh.spec().spring_stiffness * (sum2 / phases) /
                                          (mesh.spec().spring_stiffness + sum2 / phases);
    anti["both_flanks_loaded_between"] = {-mesh.preloadForce() * (1.0 + kc / k1),
                                          mesh.preloadForce() * (1.0 + k1 / kc)};
  }
  return {
      {"model", toString(mesh.model())},
      {"verified", mesh.verified()},
      {"note", mesh.verified()
                   ? ""
                   : "UNVERIFIED: Kuang & Yang (1992) coefficients and units could not be checked "
                     "against the primary paper; see docs/gear_model.md"},
      {"geometry", gearGeometryJson(mesh.geometry())},
      {"mesh_force", mesh_force},
      {"period", rows},
      {"k1", {{"mean", sum1 / phases}, {"min", min1}, {"max", max1}}},
      {"k2", {{"mean", sum2 / phases}, {"min", min2}, {"max", max2}}},
      {"ks", {{"mean", sums / phases}, {"min", mins}, {"max", maxs}}},
      {"anti_backlash", anti},
      {"iso6336",
       {{"single_stiffness_theoretical", iso.single_stiffness_theoretical},
        {"single_stiffness", iso.single_stiffness},
        {"mesh_stiffness", iso.mesh_stiffness},
        {"mesh_stiffness_helical", iso.mesh_stiffness_helical},
        {"transverse_contact_ratio", iso.transverse_contact_ratio},
        {"factors", {{"C_M", iso.c_m}, {"C_R", iso.c_r}, {"C_B", iso.c_b}}},
        {"unit", "N/m^2 per unit face width (1 N/(mm um) = 1e9 N/m^2)"}}},
      {"units", "stiffness N/m along the line of action; force N"}};
}

}  // namespace drivetrain_stiffness

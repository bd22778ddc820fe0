#include "drivetrain_stiffness/core/rig_model.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

void requireDampingRatio(std::string_view field, double value) {
  requireInClosedRange(field, value, 0.0, kMaxDampingRatio);
}

double meanMeshStiffness(const AntiBacklashMesh& mesh) {
  // The table's exact period means (AntiBacklashMesh::periodMeans): k1 + k_c while both flanks
  // carry load (seed 000 eq 1), k1 alone for an ordinary gear (no scissor spring).
  const AntiBacklashMesh::PeriodMeans& m = mesh.periodMeans();
  return m.k1 + (mesh.spec().spring_stiffness > 0 ? m.k_chain : 0.0);
}

GearRotorParameters rigRotorParameters(const RigConfig& rig, const AntiBacklashMesh& mesh,
                                       const std::array<double, 2>& bearing_stiffness,
                                       const DampingRatios& damping) {
  const DynamicsConfig& d = rig.dynamics;
  GearRotorParameters p;
  p.pinion_mass = d.pinion_mass;
  p.gear_mass = d.gear_mass;
  p.pinion_inertia = d.pinion_inertia;
  p.gear_inertia = d.gear_inertia;
  p.pinion_base_radius = mesh.geometry().baseRadius(0);
  p.gear_base_radius = mesh.geometry().baseRadius(1);
  for (int i = 0; i < 2; ++i) {
    if (!(bearing_stiffness[i] > 0.0)) {
      throwInvalid(
          std::string("bearing stiffness of the ") + (i == 0 ? "pinion" : "gear") + " shaft",
          bearing_stiffness[i],
          "the 3-DOF model needs each shaft supported (give that shaft a bearing in 'bearings:')");
    }
    p.bearing_stiffness[i] = bearing_stiffness[i];
    const double m = i == 0 ? p.pinion_mass : p.gear_mass;
    p.bearing_damping[i] = 2.0 * damping.bearing * std::sqrt(p.bearing_stiffness[i] * m);
    p.bearing_clearance[i] = d.bearing_clearance[i];
  }
  p.mesh_damping = 2.0 * damping.mesh * std::sqrt(meanMeshStiffness(mesh) * p.equivalentMass());
  return p;
}

State6 staticEquilibrium(const GearRotorModel& model, double t) {
  MeshInstant m;
  model.meshAt(t, m);  // with the torque input, if the model takes one
  const GearRotorParameters& p = model.parameters();
  const double ks = m.k_drive + m.k_back;
  const Eigen::Matrix3d k = meshBearingMatrix(ks, p.bearing_stiffness);
  // Mesh force k_s (delta - o) with delta = x + x_p - x_g - e and o the backlash an ordinary gear
  // must close on the loaded flank (b sign(F), seed 000 eq 17): e + o enters as k_s (e + o) on each
  // row.
  const bool ordinary = m.k_back == 0.0 && m.preload_force == 0.0;
  const double offset = m.te + (ordinary ? std::copysign(m.backlash, m.drive_force) : 0.0);
  const Eigen::Vector3d f(ks * offset, -ks * offset, m.drive_force + ks * offset);
  State6 y = State6::Zero();
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(k);
  if (lu.rank() < 3) {
    throw InvalidInput(
        "static equilibrium: the stiffness matrix is singular (a shaft without bearing stiffness, "
        "or no mesh stiffness)");
  }
  y.head<3>() = lu.solve(f);
  return y;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/core/resonance/operating_point_modes.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/rig_excitation.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

MeshStiffnessRange meshStiffnessRange(const AntiBacklashMesh& mesh, double mesh_force,
                                      int samples) {
  if (samples < 1) throwInvalid("samples", samples, "must be >= 1");
  requireFinite("mesh_force", mesh_force);
  MeshStiffnessRange r{INFINITY, 0.0};
  for (int i = 0; i < samples; ++i) {
    const double k = mesh.at((i + 0.5) / samples, mesh_force).composite;
    r.min = std::min(r.min, k);
    r.max = std::max(r.max, k);
  }
  return r;
}

namespace {

/// The Floquet multipliers of the rig's model at its nominal speed, linearised about the static
/// equilibrium under `torque`: the model the online dynamics integrates (DynamicsEstimator), the
/// pinion speed n [rpm] giving the mesh frequency z_p n / 60.
MeshPeriodFloquet meshPeriodFloquet(const RigConfig& rig,
                                    std::shared_ptr<const AntiBacklashMesh> mesh,
                                    const GearRotorParameters& p, double torque) {
  const DynamicsConfig& d = rig.dynamics;
  RigExcitationSpec spec;
  spec.speed = d.speed_rpm * kTwoPi / 60.0;  // [rad/s]
  spec.te_amplitude = d.transmission_error_amplitude;
  spec.backlash = d.backlash;
  spec.balanced_load = true;
  spec.torque.mean = torque;
  const auto excitation = std::make_shared<const RigExcitation>(std::move(mesh), p, spec);
  const GearRotorModel model(p, excitation);
  MeshPeriodFloquet f;
  f.mesh_frequency = excitation->meshFrequency();
  f.result = floquet(model, staticEquilibrium(model, 0.0), 0.0, 1.0 / f.mesh_frequency);
  return f;
}

}  // namespace

OperatingPointModes operatingPointModes(const RigConfig& rig, double torque) {
  if (!rig.dynamics.present)
    throw InvalidInput("dynamics: the gearbox file has no 'dynamics:' block");
  requireFinite("torque", torque);
  OperatingPointModes r;
  r.torque = torque;
  StiffnessEstimator estimator(rig);
  estimator.setTorque(torque);
  r.bearing_stiffness = estimator.shaftRadialStiffness();
  const AntiBacklashMesh& mesh = estimator.mesh();
  r.parameters = rigRotorParameters(rig, mesh, r.bearing_stiffness);
  r.mesh_mean = meanMeshStiffness(mesh);
  r.mesh_range =
      meshStiffnessRange(mesh, meshForce(rig.gears, 0, torque));  // pinion torque -> LOA force
  r.modes_mean = modalAnalysis(r.parameters, r.mesh_mean);
  r.modes_single_pair = modalAnalysis(r.parameters, r.mesh_range.min);
  r.modes_double_pair = modalAnalysis(r.parameters, r.mesh_range.max);
  if (rig.dynamics.bearing_clearance[0] == 0.0 && rig.dynamics.bearing_clearance[1] == 0.0) {
    r.floquet = meshPeriodFloquet(rig, estimator.sharedMesh(), r.parameters, torque);
  }
  return r;
}

}  // namespace drivetrain_stiffness

// The 3-DOF model of a configured rig: rotor parameters, mean mesh stiffness, static equilibrium.
#pragma once

#include <array>
#include <string_view>

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// The largest damping ratio anywhere (docs/configuration.md "Gearbox YAML", dynamics).
constexpr double kMaxDampingRatio = 1.0;
/// Throws InvalidInput naming `field` unless 0 <= value <= kMaxDampingRatio.
void requireDampingRatio(std::string_view field, double value);

/// The period mean [N/m] of k1, plus k_c for an anti-backlash gear (AntiBacklashMesh::periodMeans).
double meanMeshStiffness(const AntiBacklashMesh& mesh);

/// The model's damping ratios [-]: the `dynamics:` block's or the run-time settings'.
struct DampingRatios {
  double mesh = 0.0, bearing = 0.0;
  static DampingRatios of(const DynamicsConfig& d) {
    return {d.mesh_damping_ratio, d.bearing_damping_ratio};
  }
};

/// The rig's rotor parameters with bearing_stiffness [N/m] per shaft and damping c_s = 2 zeta
/// sqrt(k_mean m_s) (torsional), c_b = 2 zeta sqrt(k_r m) (per shaft).
GearRotorParameters rigRotorParameters(const RigConfig& rig, const AntiBacklashMesh& mesh,
                                       const std::array<double, 2>& bearing_stiffness,
                                       const DampingRatios& damping);
/// The same with the `dynamics:` block's damping ratios.
inline GearRotorParameters rigRotorParameters(const RigConfig& rig, const AntiBacklashMesh& mesh,
                                              const std::array<double, 2>& bearing_stiffness) {
  return rigRotorParameters(rig, mesh, bearing_stiffness, DampingRatios::of(rig.dynamics));
}

/// The static equilibrium K q = f of the linearised model at t [s].
State6 staticEquilibrium(const GearRotorModel& model, double t);

}  // namespace drivetrain_stiffness

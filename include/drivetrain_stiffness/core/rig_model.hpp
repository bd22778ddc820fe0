// The 3-DOF model of a configured rig: its rotor parameters (masses, radii, bearing stiffness and
// damping from the rig's `dynamics:` block), the mean mesh stiffness the damping is scaled on, and
// the static equilibrium the model starts from. Production code (the online dynamics, the
// pipeline, calibration, spectra, studies, the CLI) builds its model here; the demo scenes
// (scenes.hpp) build theirs the same way.
#pragma once

#include <array>
#include <string_view>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/gear_rotor_model.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// The damping ratios zeta of the `dynamics:` block (mesh_damping_ratio, bearing_damping_ratio),
/// one rule for the gearbox YAML, the run-time settings (parameters, dynamic_reconfigure, replay)
/// and DynamicsEstimator::setDamping: 0 <= zeta <= 1.
/// - 1 is allowed. It is critical damping of the single mode the ratio is defined on (c = 2 zeta
///   sqrt(k m), below), not of the coupled 3-DOF model, whose modes it only approaches; and where
///   a slice's eigenbasis is defective or nearly so (critically damped, or close to it from either
///   side) SlicedModalPropagator finds it ill-conditioned and dopri5 integrates that interval, as
///   it would for 0.999. Refusing exactly 1 would protect nothing, and dynamic_reconfigure (a
///   closed [min, max] slider) could not show a half-open range.
/// - Above 1 is refused: gear meshes and bearings damp at a few per cent; a ratio past critical
///   is a percentage typed for a fraction (5 for 0.05), not a rig.
constexpr double kMaxDampingRatio = 1.0;
/// Throws InvalidInput("<field> = <value>: ...") unless 0 <= value <= kMaxDampingRatio (NaN
/// included).
void requireDampingRatio(std::string_view field, double value);

/// Mean mesh stiffness over one period: k1, plus k_c for an anti-backlash gear [N/m]; the exact
/// period mean of the phase table (AntiBacklashMesh::periodMeans), the one mean every user takes.
double meanMeshStiffness(const AntiBacklashMesh& mesh);

/// The damping ratios zeta of the model [-]: the `dynamics:` block's, or the run-time settings'
/// that replace them (the rig itself is read only and shared).
struct DampingRatios {
  double mesh = 0.0, bearing = 0.0;
  static DampingRatios of(const DynamicsConfig& d) {
    return {d.mesh_damping_ratio, d.bearing_damping_ratio};
  }
};

/// The rotor parameters of a rig: masses and inertias from its `dynamics:` block, base radii from
/// the gears, the given bearing stiffness per shaft, and damping from the given ratios
/// (c_s = 2 zeta sqrt(k_mean m_s) for the torsional mode, c_b = 2 zeta sqrt(k_r m) per shaft).
GearRotorParameters rigRotorParameters(const RigConfig& rig, const AntiBacklashMesh& mesh,
                                       const std::array<double, 2>& bearing_stiffness,
                                       const DampingRatios& damping);
/// The same with the `dynamics:` block's damping ratios.
inline GearRotorParameters rigRotorParameters(const RigConfig& rig, const AntiBacklashMesh& mesh,
                                              const std::array<double, 2>& bearing_stiffness) {
  return rigRotorParameters(rig, mesh, bearing_stiffness, DampingRatios::of(rig.dynamics));
}

/// Static equilibrium of the linearised model at t (K q = f), the start state of SI scenes.
State6 staticEquilibrium(const GearRotorModel& model, double t);

}  // namespace drivetrain_stiffness

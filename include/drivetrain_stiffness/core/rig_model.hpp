// The 3-DOF model of a configured rig: its rotor parameters (masses, radii, bearing stiffness and
// damping from the rig's `dynamics:` block), the mean mesh stiffness the damping is scaled on, and
// the static equilibrium the model starts from. Production code (the online dynamics, the
// pipeline, calibration, spectra, studies, the CLI) builds its model here; the demo scenes
// (scenes.hpp) build theirs the same way.
#pragma once

#include <array>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/gear_rotor_model.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// Mean mesh stiffness over one period: k1, plus k_c for an anti-backlash gear [N/m].
double meanMeshStiffness(const AntiBacklashMesh& mesh);

/// The rotor parameters of a rig: masses and inertias from its `dynamics:` block, base radii from
/// the gears, the given bearing stiffness per shaft, and damping from the configured ratios
/// (c_s = 2 zeta sqrt(k_mean m_s) for the torsional mode, c_b = 2 zeta sqrt(k_r m) per shaft).
GearRotorParameters rigRotorParameters(const RigConfig& rig, const AntiBacklashMesh& mesh,
                                       const std::array<double, 2>& bearing_stiffness);

/// Static equilibrium of the linearised model at t (K q = f), the start state of SI scenes.
State6 staticEquilibrium(const GearRotorModel& model, double t);

}  // namespace drivetrain_stiffness

// JSON views of core results for drivetrain_cli; SI, angles in keys ending _deg in degrees.
#pragma once

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/bearing/bearing_support.hpp"

namespace drivetrain_stiffness {

/// Derived bearing data (groove-centre distance, clearances, free contact angle, Kn, contacts).
nlohmann::json bearingModelJson(const BearingSupport& support);

/// A solved equilibrium. `radial_secant` (N/m) is the secant dF_r / du_r from the same support
/// with the radial load removed, or null when the radial load is zero.
nlohmann::json bearingSolutionJson(const BearingSupport& support, const BearingSolution& solution,
                                   const nlohmann::json& radial_secant);

/// Gear geometry (radii, centre distance, contact ratio, path of contact, backlash, phases).
nlohmann::json gearGeometryJson(const SpurGearGeometry& geometry);

/// Mesh stiffness over one mesh period at `phases` evenly spaced phases under mesh force F_m [N]:
/// per phase k1, k2, k_chain, ks, pairs in contact and flank state; mean, min and max; the ISO
/// 6336-1 block per unit face width (N/m^2); the model name and whether it is verified.
nlohmann::json meshJson(const AntiBacklashMesh& mesh, int phases, double mesh_force);

}  // namespace drivetrain_stiffness

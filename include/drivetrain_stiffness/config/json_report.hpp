// JSON views of core results for drivetrain_cli and reports. SI units throughout; angles whose
// key ends in _deg are in degrees for readability.
#pragma once

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/core/bearing_support.hpp"

namespace drivetrain_stiffness {

/// Derived bearing data (groove-centre distance, clearances, free contact angle, Kn, contacts).
nlohmann::json bearingModelJson(const BearingSupport& support);

/// A solved equilibrium. `radial_secant` (N/m) is the secant dF_r / du_r from the same support
/// with the radial load removed, or null when the radial load is zero.
nlohmann::json bearingSolutionJson(const BearingSupport& support, const BearingSolution& solution,
                                   const nlohmann::json& radial_secant);

}  // namespace drivetrain_stiffness

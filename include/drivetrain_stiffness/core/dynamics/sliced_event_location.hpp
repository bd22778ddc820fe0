// Where a flank lifts or lands inside a step of the sliced model's exact solution (docs/model.md
// "Following the rig's motion"); a part of SlicedModalPropagator.
#pragma once

#include "drivetrain_stiffness/core/dynamics/sliced_modal_step.hpp"

namespace drivetrain_stiffness {
namespace sliced {

inline constexpr int kEventHalvings = 40;        ///< the location's resolution: 2^-40 of the step
inline constexpr int kEventSamples = 8;          ///< locateChange's equal lengths per step
inline constexpr double kRoundingValue = 1e-10;  ///< regimeValue's rounding: halve there

/// The first length in a step of h [s] from start (in r) to end (out of r) at which the exact
/// solution leaves r, its phasor in *e_hi.
double locateChange(const ContactRules& rules, const Slice& s, const Piece& piece, MeshRegime r,
                    int j, Complex e_theta, double w, double h, const State6& start,
                    const State6& end, Complex* e_hi);

}  // namespace sliced
}  // namespace drivetrain_stiffness

// Mesh phases in turns (one mesh period = 1).
#pragma once

#include <cmath>

namespace drivetrain_stiffness {

/// x modulo 1 in [0, 1). x - floor(x) rounds to 1.0 for an x just below an integer (-1e-17 + 1 is
/// 1.0 in a double), which would name the period's end instead of its start: that is 0.
inline double wrapTurns(double x) {
  const double w = x - std::floor(x);
  return w < 1.0 ? w : 0.0;
}

}  // namespace drivetrain_stiffness

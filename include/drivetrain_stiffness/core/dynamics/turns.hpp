#pragma once

#include <cmath>

namespace drivetrain_stiffness {

/// A mesh phase x [turns] modulo 1, in [0, 1) (an x just below an integer gives 0, not 1).
inline double wrapTurns(double x) {
  const double w = x - std::floor(x);
  return w < 1.0 ? w : 0.0;
}

}  // namespace drivetrain_stiffness

#pragma once

namespace drivetrain_stiffness {

inline constexpr double kPi = 3.141592653589793;     ///< the double nearest to pi
inline constexpr double kTwoPi = 6.283185307179586;  ///< 2 pi, exact in binary from kPi

}  // namespace drivetrain_stiffness

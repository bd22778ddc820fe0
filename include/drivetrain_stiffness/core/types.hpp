// Fixed-size Eigen types shared by the bearing model. Generalised coordinates of a bearing's inner
// ring relative to its outer ring, measured from the concentric, axially centred position (REP 103
// SI units): q = [u_x, u_y, u_z, theta_x, theta_y] in m, m, m, rad, rad; z is the bearing axis.
// Generalised loads on the inner ring: f = [F_x, F_y, F_z, M_x, M_y] in N, N, N, N·m, N·m.
#pragma once

#include <Eigen/Core>

namespace drivetrain_stiffness {

using Vector5d = Eigen::Matrix<double, 5, 1>;
using Matrix5d = Eigen::Matrix<double, 5, 5>;

enum BearingDof : int { kUx = 0, kUy = 1, kUz = 2, kThetaX = 3, kThetaY = 4 };

}  // namespace drivetrain_stiffness

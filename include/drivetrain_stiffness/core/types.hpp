// Bearing coordinates q = [u_x, u_y, u_z, theta_x, theta_y] [m, m, m, rad, rad] of the inner ring
// relative to the outer, z the bearing axis; loads f = [F_x, F_y, F_z, M_x, M_y] [N, N, N, N·m,
// N·m].
#pragma once

#include <Eigen/Core>

namespace drivetrain_stiffness {

using Vector5d = Eigen::Matrix<double, 5, 1>;
using Matrix5d = Eigen::Matrix<double, 5, 5>;

enum BearingDof : int { kUx = 0, kUy = 1, kUz = 2, kThetaX = 3, kThetaY = 4 };

}  // namespace drivetrain_stiffness

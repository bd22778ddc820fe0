// The matrix exponential of a block upper-triangular matrix M = [[X, Y], [0, Z]] as Eigen 3.4's
// MatrixBase::exp() computes it (Higham's scaling and squaring, SIAM J. Matrix Anal. Appl. 26(4)
// (2005) 1179, Table 2.3 and eqs 2.3-2.4), every product and solve block by block: with
// D = V - U, N = V + U, D_z R_z = N_z, D_x R_x = N_x, D_x R_y = N_y - D_y R_z (docs/model.md
// "Integration methods", set-up cost).
#pragma once

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <utility>

#include <Eigen/Core>
#include <Eigen/LU>

namespace drivetrain_stiffness {

template <int P, int Q>
struct BlockTriangular {
  Eigen::Matrix<double, P, P> x;
  Eigen::Matrix<double, P, Q> y;
  Eigen::Matrix<double, Q, Q> z;

  static BlockTriangular identity() {
    return {Eigen::Matrix<double, P, P>::Identity(), Eigen::Matrix<double, P, Q>::Zero(),
            Eigen::Matrix<double, Q, Q>::Identity()};
  }
  /// The blocks of a dense matrix; its lower-left block is taken as zero.
  static BlockTriangular fromDense(const Eigen::Matrix<double, P + Q, P + Q>& m) {
    return {m.template topLeftCorner<P, P>(), m.template topRightCorner<P, Q>(),
            m.template bottomRightCorner<Q, Q>()};
  }
  Eigen::Matrix<double, P + Q, P + Q> dense() const {
    Eigen::Matrix<double, P + Q, P + Q> m;
    m << x, y, Eigen::Matrix<double, Q, P>::Zero(), z;
    return m;
  }
  /// The 1-norm (largest absolute column sum), as Eigen's exp() measures it.
  double l1Norm() const {
    const double left = x.cwiseAbs().colwise().sum().maxCoeff();
    const double right = (y.cwiseAbs().colwise().sum() + z.cwiseAbs().colwise().sum()).maxCoeff();
    return std::max(left, right);
  }
};

template <int P, int Q>
BlockTriangular<P, Q> operator*(const BlockTriangular<P, Q>& a, const BlockTriangular<P, Q>& b) {
  BlockTriangular<P, Q> c;
  c.x.noalias() = a.x * b.x;
  c.y.noalias() = a.x * b.y;
  c.y.noalias() += a.y * b.z;
  c.z.noalias() = a.z * b.z;
  return c;
}

/// c0 I + c1 A + c2 B + ... as blocks (the even and odd polynomials of the Pade approximants).
template <int P, int Q>
BlockTriangular<P, Q> combine(
    double c0, std::initializer_list<std::pair<double, const BlockTriangular<P, Q>*>> terms) {
  BlockTriangular<P, Q> r{c0 * Eigen::Matrix<double, P, P>::Identity(),
                          Eigen::Matrix<double, P, Q>::Zero(),
                          c0 * Eigen::Matrix<double, Q, Q>::Identity()};
  for (const auto& t : terms) {
    r.x += t.first * t.second->x;
    r.y += t.first * t.second->y;
    r.z += t.first * t.second->z;
  }
  return r;
}

/// The width of Eigen's triangular-solver panels, max(mr, nr) (TriangularSolverMatrix.h).
inline constexpr int kTriangularPanel = Eigen::internal::gebp_traits<double, double>::mr >
                                                Eigen::internal::gebp_traits<double, double>::nr
                                            ? Eigen::internal::gebp_traits<double, double>::mr
                                            : Eigen::internal::gebp_traits<double, double>::nr;

/// lu.solve(b) for a small fixed size, the operations in the order of Eigen 3.4's own solve, so
/// the same bits (docs/model.md "Integration methods"); a vector or dynamic b goes to lu.solve.
template <int N, typename Rhs>
Eigen::Matrix<double, N, Rhs::ColsAtCompileTime> luSolve(
    const Eigen::PartialPivLU<Eigen::Matrix<double, N, N>>& lu, const Eigen::MatrixBase<Rhs>& b) {
  constexpr int C = Rhs::ColsAtCompileTime, W = kTriangularPanel;
  const Eigen::Matrix<double, N, C> rhs = b;  // evaluated once, as solve() evaluates it
  if constexpr (C == 1 || C == Eigen::Dynamic) {
    return lu.solve(rhs);  // a vector (Eigen solves it by another path) or a size unknown here
  } else {
    using Row = Eigen::Matrix<double, 1, C>;
    // Row-major, so that each row operation below runs over the columns in packets.
    Eigen::Matrix<double, N, C, Eigen::RowMajor> x = lu.permutationP() * rhs;
    const Eigen::Matrix<double, N, N>& m = lu.matrixLU();
    // L x = P b: panels of W rows from the top, then the rows below lose the panel's sum.
    for (int p0 = 0; p0 < N; p0 += W) {
      const int p1 = std::min(N, p0 + W);
      for (int k = p0; k < p1; ++k) {
        for (int r = k + 1; r < p1; ++r) x.row(r) -= m(r, k) * x.row(k);
      }
      for (int r = p1; r < N; ++r) {
        Row sum = Row::Zero();
        for (int k = p0; k < p1; ++k) sum += m(r, k) * x.row(k);
        x.row(r) += -sum;
      }
    }
    // U x = y: panels of W rows from the bottom, row k first scaled by 1 / U(k, k).
    for (int p1 = N; p1 > 0; p1 -= W) {
      const int p0 = std::max(0, p1 - W);
      for (int k = p1 - 1; k >= p0; --k) {
        x.row(k) *= 1.0 / m(k, k);
        for (int r = p0; r < k; ++r) x.row(r) -= m(r, k) * x.row(k);
      }
      for (int r = 0; r < p0; ++r) {
        Row sum = Row::Zero();
        for (int k = p0; k < p1; ++k) sum += m(r, k) * x.row(k);
        x.row(r) += -sum;
      }
    }
    return x;
  }
}

/// exp(M) for M = [[X, Y], [0, Z]], block by block.
template <int P, int Q>
BlockTriangular<P, Q> blockTriangularExp(BlockTriangular<P, Q> a) {
  using B = BlockTriangular<P, Q>;
  const double l1 = a.l1Norm();
  int squarings = 0;
  B u, v;
  if (l1 <
      9.504178996162932e-001) {  // theta_3, theta_5, theta_7: degree 3, 5 or 7 (Higham Table 2.3)
    const B a2 = a * a;
    if (l1 < 1.495585217958292e-002) {
      static constexpr double b[] = {120.0, 60.0, 12.0, 1.0};
      const B tmp = combine<P, Q>(b[1], {{b[3], &a2}});
      u = a * tmp;
      v = combine<P, Q>(b[0], {{b[2], &a2}});
    } else if (l1 < 2.539398330063230e-001) {
      static constexpr double b[] = {30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0};
      const B a4 = a2 * a2;
      const B tmp = combine<P, Q>(b[1], {{b[5], &a4}, {b[3], &a2}});
      u = a * tmp;
      v = combine<P, Q>(b[0], {{b[4], &a4}, {b[2], &a2}});
    } else {
      static constexpr double b[] = {17297280.0, 8648640.0, 1995840.0, 277200.0,
                                     25200.0,    1512.0,    56.0,      1.0};
      const B a4 = a2 * a2, a6 = a4 * a2;
      const B tmp = combine<P, Q>(b[1], {{b[7], &a6}, {b[5], &a4}, {b[3], &a2}});
      u = a * tmp;
      v = combine<P, Q>(b[0], {{b[6], &a6}, {b[4], &a4}, {b[2], &a2}});
    }
  } else if (l1 < 2.097847961257068e+000) {  // theta_9
    static constexpr double b[] = {17643225600.0, 8821612800.0, 2075673600.0, 302702400.0,
                                   30270240.0,    2162160.0,    110880.0,     3960.0,
                                   90.0,          1.0};
    const B a2 = a * a, a4 = a2 * a2, a6 = a4 * a2, a8 = a6 * a2;
    const B tmp = combine<P, Q>(b[1], {{b[9], &a8}, {b[7], &a6}, {b[5], &a4}, {b[3], &a2}});
    u = a * tmp;
    v = combine<P, Q>(b[0], {{b[8], &a8}, {b[6], &a6}, {b[4], &a4}, {b[2], &a2}});
  } else {  // degree 13 on M / 2^s with |M / 2^s|_1 below theta_13
    static constexpr double b[] = {64764752532480000.0,
                                   32382376266240000.0,
                                   7771770303897600.0,
                                   1187353796428800.0,
                                   129060195264000.0,
                                   10559470521600.0,
                                   670442572800.0,
                                   33522128640.0,
                                   1323241920.0,
                                   40840800.0,
                                   960960.0,
                                   16380.0,
                                   182.0,
                                   1.0};
    std::frexp(l1 / 5.371920351148152, &squarings);
    if (squarings < 0) squarings = 0;
    // M / 2^s as a product with 2^-s: rounds as Eigen's ldexp per coefficient.
    const double scale = std::ldexp(1.0, -squarings);
    a.x *= scale;
    a.y *= scale;
    a.z *= scale;
    const B a2 = a * a, a4 = a2 * a2, a6 = a4 * a2;
    B tmp = combine<P, Q>(0.0, {{b[13], &a6}, {b[11], &a4}, {b[9], &a2}});
    tmp = a6 * tmp;
    tmp = combine<P, Q>(b[1], {{1.0, &tmp}, {b[7], &a6}, {b[5], &a4}, {b[3], &a2}});
    u = a * tmp;
    tmp = combine<P, Q>(0.0, {{b[12], &a6}, {b[10], &a4}, {b[8], &a2}});
    tmp = a6 * tmp;
    v = combine<P, Q>(b[0], {{1.0, &tmp}, {b[6], &a6}, {b[4], &a4}, {b[2], &a2}});
  }
  // r = (V - U)^-1 (V + U), block by block.
  const Eigen::PartialPivLU<Eigen::Matrix<double, P, P>> dx(v.x - u.x);
  const Eigen::PartialPivLU<Eigen::Matrix<double, Q, Q>> dz(v.z - u.z);
  B r;
  r.z = luSolve(dz, v.z + u.z);
  r.x = luSolve(dx, v.x + u.x);
  r.y = luSolve(dx, (v.y + u.y) - (v.y - u.y) * r.z);
  for (int i = 0; i < squarings; ++i) r = r * r;
  return r;
}

}  // namespace drivetrain_stiffness

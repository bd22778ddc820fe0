// blockTriangularExp against closed forms and against Eigen's dense exponential, on every Pade
// branch (degree 3, 5, 7, 9 and 13 with squarings: the 1-norm thresholds theta_m of Higham 2005,
// Table 2.3).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include <unsupported/Eigen/MatrixFunctions>

#include "drivetrain_stiffness/core/dynamics/block_triangular_exponential.hpp"

using namespace drivetrain_stiffness;

namespace {

/// A random block upper-triangular matrix with the given 1-norm.
template <int P, int Q>
BlockTriangular<P, Q> randomWithNorm(std::mt19937& rng, double norm) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  BlockTriangular<P, Q> m;
  m.x = Eigen::Matrix<double, P, P>::NullaryExpr([&] { return u(rng); });
  m.y = Eigen::Matrix<double, P, Q>::NullaryExpr([&] { return u(rng); });
  m.z = Eigen::Matrix<double, Q, Q>::NullaryExpr([&] { return u(rng); });
  const double s = norm / m.l1Norm();
  m.x *= s;
  m.y *= s;
  m.z *= s;
  return m;
}

}  // namespace

// exp([[a, b], [0, c]]) = [[e^a, b (e^a - e^c) / (a - c)], [0, e^c]] (the 2x2 upper-triangular
// case; e.g. Higham, Functions of Matrices, SIAM 2008, eq. 4.16 with f = exp), on each Pade branch.
TEST(BlockTriangularExp, ScalarBlocksMatchTheClosedForm) {
  for (const double scale : {1e-3, 0.1, 0.5, 1.5, 4.0, 40.0}) {
    const double a = -0.7 * scale, b = 0.9 * scale, c = 0.25 * scale;
    BlockTriangular<1, 1> m;
    m.x(0, 0) = a;
    m.y(0, 0) = b;
    m.z(0, 0) = c;
    const BlockTriangular<1, 1> e = blockTriangularExp(m);
    // e^a - e^c = e^c expm1(a - c): no cancellation at small scales.
    const double coupling = b * std::exp(c) * std::expm1(a - c) / (a - c);
    EXPECT_NEAR(e.x(0, 0), std::exp(a), 1e-14 * std::exp(a)) << scale;
    EXPECT_NEAR(e.z(0, 0), std::exp(c), 1e-14 * std::exp(c)) << scale;
    EXPECT_NEAR(e.y(0, 0), coupling, 2e-14 * std::abs(coupling)) << scale;
  }
}

// A rotation generator in the X block and a nilpotent shear in the Z block (as the integrator's TE
// and torque generators): exp is the rotation by the angle and I + N exactly.
TEST(BlockTriangularExp, RotationAndShearAreExact) {
  for (const double angle : {1e-3, 0.3, 2.0, 7.5}) {
    BlockTriangular<2, 2> m;
    m.x << 0.0, angle, -angle, 0.0;
    m.y.setZero();
    m.z << 0.0, 1.0, 0.0, 0.0;
    const BlockTriangular<2, 2> e = blockTriangularExp(m);
    EXPECT_NEAR(e.x(0, 0), std::cos(angle), 1e-14);
    EXPECT_NEAR(e.x(0, 1), std::sin(angle), 1e-14);
    EXPECT_NEAR(e.x(1, 0), -std::sin(angle), 1e-14);
    EXPECT_NEAR(e.z(0, 1), 1.0, 1e-14);
    EXPECT_NEAR(e.z(1, 0), 0.0, 1e-14);
    EXPECT_TRUE(e.y.isZero(0.0));
  }
}

// The integrator's shape (6 + 5), random matrices on every branch: Eigen's dense exp() to rounding
// (normwise, relative to |exp(M)|), and the lower-left block the dense result leaves is zero.
TEST(BlockTriangularExp, AgreesWithEigensDenseExponentialOnEveryBranch) {
  std::mt19937 rng(7);
  for (const double norm : {0.01, 0.2, 0.9, 2.0, 5.0, 30.0, 200.0}) {
    for (int trial = 0; trial < 20; ++trial) {
      const BlockTriangular<6, 5> m = randomWithNorm<6, 5>(rng, norm);
      const Eigen::Matrix<double, 11, 11> dense = m.dense().exp();
      const Eigen::Matrix<double, 11, 11> ours = blockTriangularExp(m).dense();
      const double size = dense.cwiseAbs().colwise().sum().maxCoeff();
      const double diff = (ours - dense).cwiseAbs().colwise().sum().maxCoeff();
      EXPECT_LT(diff, 1e-13 * size) << "norm " << norm << ", trial " << trial;
      EXPECT_TRUE((dense.bottomLeftCorner<5, 6>().isZero(0.0)));
    }
  }
}

// exp(M) exp(-M) = I, independent of Eigen's implementation.
TEST(BlockTriangularExp, InverseIsTheExponentialOfMinusM) {
  std::mt19937 rng(11);
  for (const double norm : {0.05, 1.0, 3.0, 12.0}) {
    BlockTriangular<6, 5> m = randomWithNorm<6, 5>(rng, norm);
    const BlockTriangular<6, 5> e = blockTriangularExp(m);
    m.x = -m.x;
    m.y = -m.y;
    m.z = -m.z;
    const BlockTriangular<6, 5> f = blockTriangularExp(m);
    const Eigen::Matrix<double, 11, 11> product = (e * f).dense();
    const double bound = 1e-13 * e.dense().cwiseAbs().colwise().sum().maxCoeff() *
                         f.dense().cwiseAbs().colwise().sum().maxCoeff();
    EXPECT_LT((product - Eigen::Matrix<double, 11, 11>::Identity()).cwiseAbs().maxCoeff(), bound)
        << norm;
  }
}

// luSolve against an independent check (the residual of the system it solves) and, where Eigen's
// kernels take no fused multiply-add (this package's default build: SSE2, no -mfma), against
// Eigen's own PartialPivLU::solve bit for bit, which is the point of writing it out: the same
// operations in the same order, without the blocked solver's packing. Sizes and shapes of the
// exponential's blocks (6x6, 6x5, 5x5) and random pivots; more rows than a panel are compared bit
// for bit only without AVX, whose kernel sums a leftover row with four accumulators.
template <int N, int C>
void checkLuSolve(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix<double, N, N> a =
        Eigen::Matrix<double, N, N>::NullaryExpr([&] { return u(rng); });
    const Eigen::Matrix<double, N, C> b =
        Eigen::Matrix<double, N, C>::NullaryExpr([&] { return u(rng); });
    const Eigen::PartialPivLU<Eigen::Matrix<double, N, N>> lu(a);
    const Eigen::Matrix<double, N, C> x = luSolve(lu, b);
    // Residual relative to |A| |x| + |b| (a backward-stable solve: a small multiple of eps).
    const double scale = (a.cwiseAbs() * x.cwiseAbs() + b.cwiseAbs()).maxCoeff();
    EXPECT_LT((a * x - b).cwiseAbs().maxCoeff(), 1e-13 * scale)
        << N << "x" << C << " trial " << trial;
#ifndef EIGEN_VECTORIZE_FMA
#ifdef EIGEN_VECTORIZE_AVX
    constexpr bool comparable = N <= kTriangularPanel;
#else
    constexpr bool comparable = true;
#endif
    if (comparable) {
      const Eigen::Matrix<double, N, C> eigen = lu.solve(b);
      EXPECT_EQ(0, std::memcmp(x.data(), eigen.data(), sizeof(double) * N * C))
          << N << "x" << C << " trial " << trial;
    }
#endif
  }
}

TEST(BlockTriangularExp, WrittenOutSolveIsEigensSolve) {
  std::mt19937 rng(5);
  checkLuSolve<6, 6>(rng);
  checkLuSolve<6, 5>(rng);
  checkLuSolve<5, 5>(rng);
  checkLuSolve<3, 2>(rng);  // a single panel
  checkLuSolve<9, 4>(rng);  // three panels
}

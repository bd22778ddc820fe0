#include "drivetrain_stiffness/calibration/order_regression.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

OrderRegression::OrderRegression(int pinion_teeth, int gear_teeth) {
  if (pinion_teeth <= 0) throwInvalid("gears.teeth[0]", pinion_teeth, "must be > 0");
  if (gear_teeth <= 0) throwInvalid("gears.teeth[1]", gear_teeth, "must be > 0");
  const double r = static_cast<double>(pinion_teeth) / gear_teeth;
  for (double o : {1.0, 2.0, r, 2.0 * r}) {
    const bool known = std::any_of(orders_.begin(), orders_.begin() + orders_count_,
                                   [&](double x) { return std::abs(x - o) < 1e-9; });
    // An order on a mesh harmonic (z_p <= 2) would take the stiffness signal away: not removed.
    bool on_mesh = false;
    for (int k = 1; k <= kMeshHarmonics; ++k)
      on_mesh = on_mesh || std::abs(o - k * pinion_teeth) < 1e-9;
    if (!known && !on_mesh) orders_[orders_count_++] = o;
  }
  terms_ = 1 + 2 * orders_count_ + 2 * kMeshHarmonics;
  clear();
}

void OrderRegression::clear() {
  ata_.setZero();
  aty_.setZero();
  yty_ = 0.0;
  y0_ = 0.0;
  n_ = 0;
}

void OrderRegression::basis(double pinion_angle, double mesh_phase, Vector& a) const {
  a.setZero();
  a[0] = 1.0;
  int i = 1;
  for (int o = 0; o < orders_count_; ++o) {
    a[i++] = std::cos(orders_[o] * pinion_angle);
    a[i++] = std::sin(orders_[o] * pinion_angle);
  }
  for (int k = 1; k <= kMeshHarmonics; ++k) {
    a[i++] = std::cos(kTwoPi * k * mesh_phase);
    a[i++] = std::sin(kTwoPi * k * mesh_phase);
  }
}

void OrderRegression::add(double pinion_angle, double mesh_phase, double te) {
  // Relative to the window's first reading: the TE level (the encoders' zeros) may be far larger
  // than its variation, and y'y would cancel.
  if (n_ == 0) y0_ = te;
  const double y = te - y0_;
  Vector a;
  basis(pinion_angle, mesh_phase, a);
  ata_.selfadjointView<Eigen::Lower>().rankUpdate(a);
  aty_ += y * a;
  yty_ += y * y;
  ++n_;
}

bool OrderRegression::solve(Fit& out) const {
  const int p = terms_;
  if (n_ < 4 * p) return false;
  // Scale to unit diagonal before the factorisation (the columns are O(1) already; this guards the
  // condition estimate), then refuse an ill-conditioned window: the readings did not span the
  // orders (a window shorter than a gear turn), so the coefficients would trade off freely.
  const Matrix full = ata_.selfadjointView<Eigen::Lower>();
  Eigen::Matrix<double, kMaxTerms, 1> d = full.diagonal().cwiseSqrt();
  for (int i = p; i < kMaxTerms; ++i) d[i] = 1.0;
  Matrix scaled = d.cwiseInverse().asDiagonal() * full * d.cwiseInverse().asDiagonal();
  for (int i = p; i < kMaxTerms; ++i) scaled(i, i) = 1.0;  // unused terms: identity, decoupled
  Eigen::LDLT<Matrix> ldlt(scaled);
  if (ldlt.info() != Eigen::Success) return false;
  const auto diag = ldlt.vectorD();
  const double dmax = diag.head(p).maxCoeff(), dmin = diag.head(p).minCoeff();
  if (!(dmin > 1e-6 * dmax)) return false;
  Vector rhs = aty_.cwiseQuotient(d);
  for (int i = p; i < kMaxTerms; ++i) rhs[i] = 0.0;
  const Vector z = ldlt.solve(rhs);
  const Vector beta = z.cwiseQuotient(d);
  // Residual sum of squares from the normal equations: y'y - beta' A'y.
  const double rss = std::max(0.0, yty_ - beta.head(p).dot(aty_.head(p)));
  const double sigma2 = rss / static_cast<double>(n_ - p);
  // Cov(beta) = sigma^2 (A'A)^-1: its diagonal from the scaled inverse.
  const Matrix inv = ldlt.solve(Matrix::Identity());
  out.coefficients = beta;
  out.coefficients[0] += y0_;
  out.mean = out.coefficients[0];
  out.mean_std = std::sqrt(sigma2 * inv(0, 0)) / d[0];
  const int first = 1 + 2 * orders_count_;
  double var = 0.0;
  for (int k = 0; k < kMeshHarmonics; ++k) {
    const int c = first + 2 * k;
    out.harmonics[k] = {beta[c], -beta[c + 1]};
    if (k < 2)
      var = std::max({var, sigma2 * inv(c, c) / (d[c] * d[c]),
                      sigma2 * inv(c + 1, c + 1) / (d[c + 1] * d[c + 1])});
  }
  out.harmonic_std = std::sqrt(var);
  out.residual_rms = std::sqrt(rss / static_cast<double>(n_));
  return true;
}

double OrderRegression::orders(const Fit& fit, double pinion_angle) const {
  double x = 0.0;
  for (int o = 0; o < orders_count_; ++o) {
    x += fit.coefficients[1 + 2 * o] * std::cos(orders_[o] * pinion_angle) +
         fit.coefficients[2 + 2 * o] * std::sin(orders_[o] * pinion_angle);
  }
  return x;
}

}  // namespace drivetrain_stiffness

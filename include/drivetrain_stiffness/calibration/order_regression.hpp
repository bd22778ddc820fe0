// Angle-domain least squares over one window of encoder readings (docs/calibration.md, "Measured
// TE"): the measured TE is fitted with a mean, each shaft's 1x and 2x orders (eccentricity and
// encoder mounting: not stiffness) and the first mesh harmonics,
//   x(theta) = b0 + sum_o [a_o cos(o theta_p) + b_o sin(o theta_p)] + sum_k [c_k cos(2 pi k phi) +
//   d_k sin(2 pi k phi)],
// with o in {1, 2, z_p/z_g, 2 z_p/z_g} pinion orders (the gear's 1x and 2x, since theta_g =
// -(z_p/z_g) theta_p to micro-radians), orders that coincide merged (a 2:1 pair's pinion 1x is the
// gear's 2x), and phi the mesh phase. This is the order-tracking removal of shaft orders done as
// one regression rather than resampling and notching: the readings need not be uniform in angle,
// and a window that does not hold whole periods of every order is handled by the fit instead of
// leaking. The normal equations are accumulated per reading in fixed-size storage: no allocation,
// no samples kept.
#pragma once

#include <array>
#include <complex>

#include <Eigen/Core>

namespace drivetrain_stiffness {

class OrderRegression {
 public:
  static constexpr int kMaxOrders = 4;
  static constexpr int kMeshHarmonics = 4;  ///< fitted (the features use the first two)
  static constexpr int kMaxTerms = 1 + 2 * kMaxOrders + 2 * kMeshHarmonics;
  using Vector = Eigen::Matrix<double, kMaxTerms, 1>;
  using Matrix = Eigen::Matrix<double, kMaxTerms, kMaxTerms>;

  /// Teeth of pinion and gear (> 0).
  OrderRegression(int pinion_teeth, int gear_teeth);

  void clear();
  /// One reading: pinion angle [rad] (unwrapped), mesh phase [-], measured TE [m].
  void add(double pinion_angle, double mesh_phase, double te);
  long count() const { return n_; }

  struct Fit {
    double mean = 0.0;                                           ///< b0 [m]
    std::array<std::complex<double>, kMeshHarmonics> harmonics;  ///< c_k - i d_k [m]
    double mean_std = 0.0,
           harmonic_std = 0.0;             ///< standard deviations of b0 and of each c_k, d_k [m]
    double residual_rms = 0.0;             ///< [m]
    Vector coefficients = Vector::Zero();  ///< in basis order (the orders follow the mean)
  };
  /// Solves the window's least squares; false when it is not determined (too few readings, or
  /// the readings do not span the orders: a rank-deficient or ill-conditioned fit).
  bool solve(Fit& out) const;
  /// The fitted shaft orders at `pinion_angle` (to remove them reading by reading) [m].
  double orders(const Fit& fit, double pinion_angle) const;
  int terms() const { return terms_; }
  int orderCount() const { return orders_count_; }

 private:
  void basis(double pinion_angle, double mesh_phase, Vector& a) const;

  std::array<double, kMaxOrders> orders_{};
  int orders_count_ = 0;
  int terms_ = 0;
  Matrix ata_ = Matrix::Zero();
  Vector aty_ = Vector::Zero();
  double yty_ = 0.0, y0_ = 0.0;
  long n_ = 0;
};

}  // namespace drivetrain_stiffness

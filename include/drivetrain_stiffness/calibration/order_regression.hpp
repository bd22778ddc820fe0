// Angle-domain least squares over one window of encoder readings: a mean, each shaft's 1x and 2x
// orders and the first mesh harmonics (docs/calibration.md "1. Measured TE", step 3). No
// allocation, no samples kept.
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
    double mean_std = 0.0, harmonic_std = 0.0;                   ///< of b0 and of each c_k, d_k [m]
    double residual_rms = 0.0;                                   ///< [m]
    Vector coefficients = Vector::Zero();                        ///< in basis order
  };
  /// Solves the window's least squares; false when rank-deficient or ill-conditioned.
  bool solve(Fit& out) const;
  /// The fitted shaft orders [m] at `pinion_angle` [rad].
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

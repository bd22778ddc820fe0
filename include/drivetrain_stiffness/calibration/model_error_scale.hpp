// The rig's model error estimated from the windows' innovations, and the calibration's covariance
// it implies: docs/calibration.md "3. The estimator", "Bands that widen when the rig's model error
// exceeds the allowance". Joseph form with the true noise, P+ = (I - K H) P- (I - K H)' + K (N + c
// M) K' (Gelb, Applied Optimal Estimation, 1974, sec. 7.2), carried as P_N + sum_j c_j P_Mj.
#pragma once

#include <array>
#include <cstdint>

#include "drivetrain_stiffness/calibration/static_te_model.hpp"

namespace drivetrain_stiffness {

class ModelErrorScale {
 public:
  static constexpr int kGrid = 31;  ///< c = 10^(-4 + 6 k / 30), 1e-4 to 1e2
  static constexpr std::uint64_t kMinWindows = 10;
  using FeatureRows = Eigen::Matrix<double, kFeatureSize, kCalibrationSize>;
  using Gain = Eigen::Matrix<double, kCalibrationSize, kFeatureSize>;

  ModelErrorScale() { reset(CalibrationMatrix::Zero()); }
  /// Starts at the prior covariance.
  void reset(const CalibrationMatrix& prior);
  /// Adds the random walk between updates (the filter's Q).
  void predict(const CalibrationMatrix& process_noise) { noise_part_ += process_noise; }
  /// diag(H P_true- H') + N: each feature's innovation variance without the model error.
  FeatureVector innovationVariance(const FeatureRows& H, const FeatureVector& noise) const;
  /// One accepted window: innovation nu, innovationVariance before the update, diagonals N and M,
  /// and the update's gain K and Jacobian H.
  void update(const FeatureVector& nu, const FeatureVector& variance, const FeatureVector& noise,
              const FeatureVector& model, const Gain& K, const FeatureRows& H);
  /// An update by another kind of measurement (no allowance of these features in its noise):
  /// P_N takes (I - K H) P_N (I - K H)' + K R K', each P_Mj (I - K H) P_Mj (I - K H)'. `ikh`:
  /// I - K H, `krk`: K R K'.
  void absorb(const CalibrationMatrix& ikh, const CalibrationMatrix& krk);
  /// c per feature (1 before kMinWindows windows).
  FeatureVector scale() const;
  /// P_true at max(scale(), min_scale) per feature.
  CalibrationMatrix covariance(double min_scale = 0.0) const;

 private:
  static double gridValue(int k);
  std::array<std::array<double, kGrid>, kFeatureSize> score_{};
  CalibrationMatrix noise_part_ = CalibrationMatrix::Zero();  ///< P_N (the prior included)
  std::array<CalibrationMatrix, kFeatureSize> model_part_{};  ///< P_Mj
  std::array<std::uint64_t, kFeatureSize> scored_{};          ///< windows with an allowance
  std::uint64_t windows_ = 0;
};

}  // namespace drivetrain_stiffness

// How large the model error is on this rig, estimated from the windows' innovations, and what
// that makes the covariance of the calibration's estimate (docs/calibration.md, "Bands that match
// the rig's model error").
//
// The filter weighs every window with R = N + M: N the fit's, the baseline's and the floor's
// variance, M = (model_error x predicted feature)^2 (times the repeats at an operating point) the
// configured allowance, a fixed guess of how far the static model misses a rig. The filter keeps
// that weighting: it makes the estimate robust (with a tighter allowance it trusted early windows
// too much and gated the reversal's, docs/calibration.md §6). What it reports need not: if the
// rig's model error is c M, the filter is a mismatched (suboptimal) Kalman filter, and the
// covariance of its estimate follows from the same gains in the Joseph form with the true noise
// (Gelb, "Applied Optimal Estimation", 1974, §7.2, sensitivity of a suboptimal filter):
//
//     P_true+ = (I - K H) P_true- (I - K H)' + K (N + c M) K',    P_true- = P_true+ + Q.
//
// It is linear in c, so it is carried as P_true = P_N + sum_j c_j P_Mj (one term per feature j:
// mean TE, |C_1|, |C_2|), and c may be re-estimated at any time without replaying the windows.
// With c = 1 it is the filter's own covariance.
//
// c_j is estimated from the innovations nu_ij, whose variance is a_ij + c_j M_ij, as the root of
// the maximum-likelihood score
//
//     sum_i M_ij (nu_ij^2 - (a_ij + c M_ij)) / (a_ij + c M_ij)^2 = 0,
//
// a plug-in approximation: a_ij = diag(H P_true- H') + N is taken at the running estimate of c
// when the window arrives (c = 1 for the first ones), not as a function of each c tried. The score
// is kept on a fixed grid of c (allocation-free), the root interpolated in log c and clamped to
// the grid's ends (1e-4 to 1e2: the model error's std between 1 % and 10x the allowance's). Windows
// where the parameters' uncertainty dominates the innovation (the early ones) weigh little. Before
// kMinWindows accepted windows, and for a feature that never had an allowance, c = 1. Windows the
// calibrator's NIS gate rejects are not counted: the largest innovations are left out, so a c
// above 1 comes out low (the bands widen too little rather than too much).
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
  /// Starts at the prior covariance (state coordinates).
  void reset(const CalibrationMatrix& prior);
  /// The random walk between updates (the filter's Q).
  void predict(const CalibrationMatrix& process_noise) { noise_part_ += process_noise; }
  /// The variance of each feature's innovation without the model error: diag(H P_true- H') + N.
  FeatureVector innovationVariance(const FeatureRows& H, const FeatureVector& noise) const;
  /// One accepted window: its innovation, the variance above for it (before the update), N and M
  /// (diagonals), the gain and the Jacobian the update used (state coordinates).
  void update(const FeatureVector& nu, const FeatureVector& variance, const FeatureVector& noise,
              const FeatureVector& model, const Gain& K, const FeatureRows& H);
  /// c per feature (1 before kMinWindows windows).
  FeatureVector scale() const;
  /// P_true at max(scale(), min_scale) per feature: the calibrator passes 1 (bands only widen).
  CalibrationMatrix covariance(double min_scale = 0.0) const;

 private:
  static double gridValue(int k);
  std::array<std::array<double, kGrid>, kFeatureSize> score_{};
  CalibrationMatrix noise_part_ = CalibrationMatrix::Zero();  ///< P_N (the prior included)
  std::array<CalibrationMatrix, kFeatureSize> model_part_{};  ///< P_Mj
  std::array<std::uint64_t, kFeatureSize> scored_{};  ///< windows with an allowance, per feature
  std::uint64_t windows_ = 0;
};

}  // namespace drivetrain_stiffness

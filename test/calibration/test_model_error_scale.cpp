// ModelErrorScale (model_error_scale.hpp) on a linear Gaussian problem whose truth is known: a
// Kalman filter weighs its measurements with R = N + M (the configured allowance M) while the
// measurements' true noise is N + c M. Checked against the laws of the problem, not against our
// own output: the maximum-likelihood c is consistent (it converges to the true c), the reported
// covariance is the estimate's real one (the errors, divided by the reported std, have unit
// variance over independent trials, where the filter's own covariance does not), and with c = 1 it
// is the filter's own covariance.
#include <cmath>
#include <iostream>
#include <random>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "drivetrain_stiffness/calibration/model_error_scale.hpp"

namespace drivetrain_stiffness {
namespace {

using Rows = ModelErrorScale::FeatureRows;
using Gain = ModelErrorScale::Gain;

struct Trial {
  CalibrationVector truth, estimate;
  CalibrationMatrix filter;  ///< the filter's own covariance (Joseph form with R = N + M)
  ModelErrorScale scale;
};

/// One run of `windows` measurements z = H theta + e, e_j ~ N(0, N_j + c_true M_j), through a
/// Kalman filter with R = N + M; ModelErrorScale fed as the calibrator feeds it.
Trial run(std::mt19937_64& rng, int windows, double c_true) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.5, 1.5);
  Trial t;
  const CalibrationMatrix prior = CalibrationMatrix::Identity();
  for (int i = 0; i < kCalibrationSize; ++i) t.truth[i] = normal(rng);  // drawn from the prior
  t.estimate.setZero();
  t.filter = prior;
  t.scale.reset(prior);
  for (int w = 0; w < windows; ++w) {
    Rows H;
    for (int j = 0; j < kFeatureSize; ++j) {
      for (int i = 0; i < kCalibrationSize; ++i) H(j, i) = normal(rng);
    }
    FeatureVector noise, model, z;
    for (int j = 0; j < kFeatureSize; ++j) {
      noise[j] = 0.01 * uniform(rng);  // measured noise, as a window fit's variance
      model[j] = 0.25 * uniform(rng);  // the configured allowance, 25x the noise
      z[j] = H.row(j).dot(t.truth) + std::sqrt(noise[j] + c_true * model[j]) * normal(rng);
    }
    t.scale.predict(CalibrationMatrix::Zero());
    const FeatureVector variance = t.scale.innovationVariance(H, noise);
    const Eigen::Matrix<double, kFeatureSize, kFeatureSize> R = (noise + model).asDiagonal();
    const Eigen::Matrix<double, kFeatureSize, kFeatureSize> S = H * t.filter * H.transpose() + R;
    const Gain K = t.filter * H.transpose() * S.inverse();
    const FeatureVector innovation = z - H * t.estimate;
    t.estimate += K * innovation;
    const CalibrationMatrix IKH = CalibrationMatrix::Identity() - K * H;
    t.filter = (IKH * t.filter * IKH.transpose() + K * R * K.transpose()).eval();
    t.scale.update(innovation, variance, noise, model, K, H);
  }
  return t;
}

TEST(ModelErrorScale, FindsTheTrueModelErrorBelowAndAboveTheAllowance) {
  std::mt19937_64 rng(11);
  for (double c_true : {0.04, 1.0, 4.0}) {
    const Trial t = run(rng, 3000, c_true);
    for (int j = 0; j < kFeatureSize; ++j) {
      // 3000 windows: the ML estimate's relative spread is about sqrt(2 / 3000) = 2.6 % where the
      // model error dominates each innovation, more where the noise does (c = 0.04: 1/1 of it).
      EXPECT_NEAR(t.scale.scale()[j] / c_true, 1.0, 0.2)
          << "feature " << j << ", true c " << c_true;
    }
  }
}

TEST(ModelErrorScale, ReportsTheEstimatesRealCovariance) {
  // 400 independent rigs of 60 windows each with a true model error of 4 % of the allowance: the
  // errors over the reported std have unit variance (chi^2 with 400 dof: mean 1 +- 0.07 at 1
  // sigma), the filter's own std is far too wide (its R holds the whole allowance).
  std::mt19937_64 rng(5);
  const int trials = 400;
  double reported = 0.0, filter = 0.0;
  int count = 0;
  for (int n = 0; n < trials; ++n) {
    const Trial t = run(rng, 60, 0.04);
    const CalibrationMatrix P = t.scale.covariance();
    for (int i = 0; i < kCalibrationSize; ++i) {
      const double e = t.estimate[i] - t.truth[i];
      reported += e * e / P(i, i);
      filter += e * e / t.filter(i, i);
      ++count;
    }
  }
  reported /= count;
  filter /= count;
  std::cout << "mean (error / std)^2 over " << count << ": reported " << reported
            << ", filter's own " << filter << "\n";
  EXPECT_NEAR(reported, 1.0,
              0.25);       // c is estimated per rig from 60 windows: a little wider than 0.07
  EXPECT_LT(filter, 0.3);  // the allowance's bands (R holds 25x the true model error): far too wide
}

TEST(ModelErrorScale, IsTheFiltersOwnCovarianceUntilItHasEnoughWindows) {
  std::mt19937_64 rng(3);
  const Trial t = run(rng, static_cast<int>(ModelErrorScale::kMinWindows) - 1, 0.04);
  EXPECT_EQ(t.scale.scale(), FeatureVector::Ones());
  // c = 1: N + M is the filter's R, so the two Joseph recursions are one.
  EXPECT_LT((t.scale.covariance() - t.filter).norm(), 1e-12 * t.filter.norm());
}

TEST(ModelErrorScale, AnotherMeasurementsUpdateHoldsAtEveryScale) {
  // A measurement of another kind (the natural frequencies: docs/calibration.md "Natural
  // frequencies") with gain K, Jacobian H and a noise R it knows, after windows that show c = 4:
  // the estimate's real covariance is the Joseph form of the real covariance before it, whatever c
  // the features' model error has: (I - K H) P(c) (I - K H)' + K R K'.
  std::mt19937_64 rng(5);
  Trial t = run(rng, 60, 4.0);
  ASSERT_GT(t.scale.scale().maxCoeff(), 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Matrix<double, 2, kCalibrationSize> H;
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < kCalibrationSize; ++i) H(j, i) = normal(rng);
  }
  const Eigen::Matrix2d R = Eigen::Vector2d(0.02, 0.05).asDiagonal();
  const CalibrationMatrix P = t.scale.covariance(1.0);
  const Eigen::Matrix<double, kCalibrationSize, 2> K =
      P * H.transpose() * (H * P * H.transpose() + R).inverse();
  const CalibrationMatrix IKH = CalibrationMatrix::Identity() - K * H;
  const CalibrationMatrix KRK = K * R * K.transpose();
  const CalibrationMatrix before_own = t.scale.covariance(0.0), before_wide = P;
  t.scale.absorb(IKH, KRK);
  const CalibrationMatrix own = IKH * before_own * IKH.transpose() + KRK;
  const CalibrationMatrix wide = IKH * before_wide * IKH.transpose() + KRK;
  EXPECT_LT((t.scale.covariance(0.0) - own).norm(), 1e-12 * own.norm());
  EXPECT_LT((t.scale.covariance(1.0) - wide).norm(), 1e-12 * wide.norm());
  EXPECT_LT(wide.trace(), before_wide.trace());  // the other measurement's information stays
}

}  // namespace
}  // namespace drivetrain_stiffness

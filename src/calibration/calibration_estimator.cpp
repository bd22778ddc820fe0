#include "drivetrain_stiffness/calibration/calibration_estimator.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace drivetrain_stiffness {

namespace {

/// Upper 0.1 % points of the chi-square distribution with 1, 2 and 3 degrees of freedom
/// (NIST/SEMATECH e-Handbook of Statistical Methods, sec. 1.3.6.7.4, "Critical values of the
/// chi-square distribution", column 0.999).
constexpr double kChiSquare999[3] = {10.828, 13.816, 16.266};

/// Gauss-Newton relinearisations of one record of natural frequencies at most: near a veering the
/// cost falls slowly (a record of the validation's rig 44 still lowered it at the sixth) [-].
constexpr int kModalIterations = 8;

}  // namespace

CalibrationEstimator::CalibrationEstimator(const CalibrationConfig& config,
                                           const CalibrationVector& mean,
                                           const CalibrationVector& prior_std,
                                           const CalibrationVector& reference_std)
    : config_(config) {
  // The prior in the state's coordinates: c = 1/s, std(c) = std(s) / s^2 (first order).
  state_ = mean;
  prior_std_ = prior_std;
  reference_std_ = reference_std;
  for (int i : {kPinionBearingScale, kGearBearingScale}) {
    state_[i] = 1.0 / mean[i];
    prior_std_[i] = prior_std[i] / (mean[i] * mean[i]);
    reference_std_[i] = reference_std[i] / (mean[i] * mean[i]);
  }
  covariance_ = prior_std_.cwiseAbs2().asDiagonal();
  model_error_.reset(covariance_);
}

CalibrationVector CalibrationEstimator::toParameters(const CalibrationVector& state) {
  CalibrationVector p = state;
  p[kPinionBearingScale] = 1.0 / state[kPinionBearingScale];
  p[kGearBearingScale] = 1.0 / state[kGearBearingScale];
  return p;
}

CalibrationMatrix CalibrationEstimator::parameterJacobian(const CalibrationVector& state) {
  CalibrationMatrix J = CalibrationMatrix::Identity();
  for (int i : {kPinionBearingScale, kGearBearingScale}) J(i, i) = -1.0 / (state[i] * state[i]);
  return J;
}

CalibrationMatrix CalibrationEstimator::filterCovariance() const {
  const CalibrationMatrix J = parameterJacobian(state_);
  return J * covariance_ * J.transpose();
}

void CalibrationEstimator::bound(CalibrationVector& state) {
  // Physical bounds: scales in [0.05, 20) as the YAML loader's, a preload torque >= 0.
  state[kMeshScale] = std::clamp(state[kMeshScale], 0.05, 19.9);
  for (int i : {kPinionBearingScale, kGearBearingScale})
    state[i] = std::clamp(state[i], 1.0 / 19.9, 1.0 / 0.05);
  state[kPreloadTorque] = std::max(0.0, state[kPreloadTorque]);
}

CalibrationMatrix CalibrationEstimator::processNoise(double t) const {
  const double dt = has_update_t_ ? std::max(0.0, t - last_update_t_) : 0.0;
  const CalibrationVector walk = (prior_std_.array() > 0.0).select(reference_std_, 0.0);
  return ((config_.drift * config_.drift * dt) * walk.cwiseAbs2()).asDiagonal();
}

bool CalibrationEstimator::iteratedUpdate(const StateMeasurement& measurement,
                                          const CalibrationMatrix& prior,
                                          const MeasurementMatrix& R, const MeasurementVector& z,
                                          const MeasurementVector& h0, const IterationRule& rule,
                                          MeasurementRows& H, MeasurementGain& K,
                                          CalibrationVector& theta) const {
  // Iterated EKF (Gauss-Newton on the posterior mode): relinearise at the new estimate. With the
  // line search, a step is taken only where it lowers the posterior's cost (prior term plus the
  // measurement's residual), halved up to 6 times otherwise (backtracking line search, Nocedal &
  // Wright 2006, Algorithm 3.1): where the measurement bends sharply a full step can overshoot.
  CalibrationMatrix prior_held = prior;  // the prior term over the estimated parameters only
  if (rule.line_search) {
    for (int i = 0; i < kCalibrationSize; ++i)
      if (!(prior_std_[i] > 0.0)) {
        prior_held.row(i).setZero();
        prior_held.col(i).setZero();
        prior_held(i, i) = 1.0;
      }
  }
  const Eigen::LDLT<CalibrationMatrix> prior_ldlt = rule.line_search
                                                        ? Eigen::LDLT<CalibrationMatrix>(prior_held)
                                                        : Eigen::LDLT<CalibrationMatrix>();
  auto cost = [&](const CalibrationVector& state, const MeasurementVector& h) {
    const CalibrationVector d = state - state_;
    double c = d.dot(prior_ldlt.solve(d));
    for (std::size_t j = 0; j < rule.rows; ++j) c += (z[j] - h[j]) * (z[j] - h[j]) / R(j, j);
    return c;
  };
  theta = state_;
  MeasurementVector h = h0;
  double current = rule.line_search ? cost(theta, h) : 0.0;
  for (int iteration = 0; iteration < rule.iterations; ++iteration) {
    if (iteration > 0) measurement.jacobian(theta, H);
    const MeasurementMatrix Si = H * prior * H.transpose() + R;
    K = prior * H.transpose() * Si.inverse();
    CalibrationVector next = state_ + K * (z - h - H * (state_ - theta));
    bound(next);
    MeasurementVector h_next = measurement.predict(next);
    if (rule.line_search) {
      double next_cost = cost(next, h_next);
      const CalibrationVector step = next - theta;
      for (int halving = 1; halving <= 6 && !(next_cost <= current); ++halving) {
        next = theta + std::ldexp(1.0, -halving) * step;
        bound(next);
        h_next = measurement.predict(next);
        next_cost = cost(next, h_next);
      }
      if (!(next_cost <= current)) {
        if (iteration > 0) break;
        return false;
      }
      current = next_cost;
    }
    const double moved =
        ((next - theta).cwiseQuotient(prior_std_.cwiseMax(1e-300))).cwiseAbs().maxCoeff();
    theta = next;
    h = h_next;
    if (moved < 1e-6) break;
  }
  return true;
}

bool CalibrationEstimator::updateFeatures(const StateMeasurement& features, const FeatureVector& z,
                                          const FeatureVector& z_std, double t, double repeats,
                                          FeatureUpdate& out) {
  // Random walk since the last update (a preload that relaxes, wear): relative to the drawing's
  // spread (the prior's, unless a calibrated gearbox keeps the drawing's as reference_std). Held
  // parameters (prior std 0) do not walk.
  const CalibrationMatrix Q = processNoise(t);
  const CalibrationMatrix prior = covariance_ + Q;

  // Measurement noise: the window's own, the relative model error and the floor
  // (docs/calibration.md). The model error repeats at an operating point: the n-th window there
  // carries n times its variance, so a long dwell adds no more than one window's worth of model
  // information. N (the fit's, the baseline's and the floor's variance) and M (the model error)
  // apart, for model_error_ (model_error_scale.hpp).
  MeasurementMatrix R = MeasurementMatrix::Zero();
  const FeatureVector h0 = features.predict(state_);
  FeatureVector noise, model_variance;
  for (int i = 0; i < kFeatureSize; ++i) {
    const double model = config_.model_error * std::abs(h0[i]);
    noise[i] = z_std[i] * z_std[i] + config_.te_noise_floor * config_.te_noise_floor;
    model_variance[i] = repeats * model * model;
    // R sums the fit's variance, the model error and the floor in this order, not as noise +
    // model_variance.
    R(i, i) =
        z_std[i] * z_std[i] + model_variance[i] + config_.te_noise_floor * config_.te_noise_floor;
  }
  MeasurementRows H;
  features.jacobian(state_, H);
  const FeatureVector innovation = z - h0;
  const MeasurementMatrix S = H * prior * H.transpose() + R;
  out.nis = innovation.dot(S.ldlt().solve(innovation));
  out.predicted = h0;
  out.feature_std = R.diagonal().cwiseSqrt();
  if (!(out.nis <= config_.gate)) return false;  // also refuses a NaN
  model_error_.predict(Q);
  const FeatureVector variance =
      model_error_.innovationVariance(H, noise);  // before the update, at the prior's H
  MeasurementGain K;
  CalibrationVector theta;
  iteratedUpdate(features, prior, R, z, h0, IterationRule{}, H, K, theta);
  // Joseph form: stays symmetric positive semi-definite whatever the rounding.
  const CalibrationMatrix IKH = CalibrationMatrix::Identity() - K * H;
  covariance_ = IKH * prior * IKH.transpose() + K * R * K.transpose();
  covariance_ = 0.5 * (covariance_ + covariance_.transpose()).eval();
  model_error_.update(innovation, variance, noise, model_variance, K, H);
  state_ = theta;
  last_update_t_ = t;
  has_update_t_ = true;
  return true;
}

WindowOutcome CalibrationEstimator::updateFrequencies(const StateMeasurement& modes,
                                                      const MeasurementVector& z,
                                                      const MeasurementVector& z_std,
                                                      const std::array<int, 3>& mode,
                                                      std::size_t count, double t, double& nis) {
  const CalibrationMatrix Q = processNoise(t);
  const CalibrationMatrix prior = covariance_ + Q;
  const MeasurementVector h0 = modes.predict(state_);
  MeasurementRows H;
  modes.jacobian(state_, H);
  // No parameter that moves these modes is estimated: nothing to learn from the record.
  if (H.cwiseAbs().maxCoeff() == 0.0) return WindowOutcome::kNone;
  // Measurement noise: the identification's variance and the relative model error of a natural
  // frequency (masses, inertias, the housing), which every record of the same mode shares: the
  // n-th record of a mode carries n times its variance. Unused slots: unit variance, no row.
  MeasurementMatrix R = MeasurementMatrix::Identity();
  for (std::size_t j = 0; j < count; ++j) {
    const double repeats = static_cast<double>(modal_count_[static_cast<std::size_t>(mode[j])] + 1);
    const double model = config_.modal_model_error * h0[j];
    R(j, j) = z_std[j] * z_std[j] + repeats * model * model;
  }
  const MeasurementVector innovation = z - h0;
  const MeasurementMatrix S = H * prior * H.transpose() + R;
  nis = innovation.dot(S.ldlt().solve(innovation));
  if (!(nis <= kChiSquare999[count - 1])) return WindowOutcome::kGated;  // also refuses a NaN
  // Iterated EKF with the line search, the frequencies being nonlinear in the state (f ~ sqrt(k),
  // k ~ 1/c): near a veering the frequencies bend sharply. A first step that finds no lower cost
  // gates the record: the model cannot follow it from the estimate.
  MeasurementGain K;
  CalibrationVector theta;
  if (!iteratedUpdate(modes, prior, R, z, h0, IterationRule{kModalIterations, true, count}, H, K,
                      theta)) {
    return WindowOutcome::kGated;
  }
  // Joseph form, and the same gain and noise on the model-error scaling's covariance: the
  // frequencies carry no allowance of the TE features, so their information stays whatever c.
  const CalibrationMatrix IKH = CalibrationMatrix::Identity() - K * H;
  const CalibrationMatrix KRK = K * R * K.transpose();
  covariance_ = IKH * prior * IKH.transpose() + KRK;
  covariance_ = 0.5 * (covariance_ + covariance_.transpose()).eval();
  model_error_.predict(Q);
  model_error_.absorb(IKH, KRK);
  state_ = theta;
  last_update_t_ = has_update_t_ ? std::max(last_update_t_, t) : t;
  has_update_t_ = true;
  for (std::size_t j = 0; j < count; ++j) ++modal_count_[static_cast<std::size_t>(mode[j])];
  return WindowOutcome::kUpdated;
}

}  // namespace drivetrain_stiffness

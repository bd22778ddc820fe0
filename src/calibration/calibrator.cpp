#include "drivetrain_stiffness/calibration/calibrator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

namespace {
constexpr double k95 = 1.959963984540054;  // two-sided 95 % of the normal distribution
}  // namespace

namespace {
const RigConfig& required(const std::shared_ptr<const RigConfig>& rig) {
  if (!rig) throw std::invalid_argument("Calibrator: no rig");  // a caller's bug, not bad data
  return *rig;
}
}  // namespace

Calibrator::Calibrator(const RigConfig& rig) : Calibrator(std::make_shared<const RigConfig>(rig)) {}

Calibrator::Calibrator(std::shared_ptr<const RigConfig> shared_rig,
                       std::shared_ptr<const AntiBacklashMesh> mesh)
    : rig_(std::move(shared_rig)),
      config_(required(rig_).calibration),
      model_(*rig_, std::move(mesh)),
      windows_(*rig_, model_),
      report_(windows_.windowAngle(), config_.baseline_torque) {
  const RigConfig& rig = *rig_;
  if (!config_.present) throw InvalidInput("calibration: the gearbox has no calibration block");
  if (!rig.dynamics.present)
    throw InvalidInput("calibration: needs the gearbox's dynamics block (masses for the modes)");
  const CalibrationConfig& c = config_;
  CalibrationVector mean;
  mean << c.mesh_stiffness_scale.mean, c.pinion_bearing_scale.mean, c.gear_bearing_scale.mean,
      c.preload_torque.mean, c.te_offset.mean;
  estimate_.prior_std << c.mesh_stiffness_scale.std, c.pinion_bearing_scale.std,
      c.gear_bearing_scale.std, c.preload_torque.std, c.te_offset.std;
  CalibrationVector reference;
  reference << c.mesh_stiffness_scale.reference(), c.pinion_bearing_scale.reference(),
      c.gear_bearing_scale.reference(), c.preload_torque.reference(), c.te_offset.reference();
  if (!(rig.anti_backlash.spring_stiffness > 0.0)) {  // no scissor spring
    estimate_.prior_std[kPreloadTorque] = 0.0;
    reference[kPreloadTorque] = 0.0;
  }
  // The prior in the state's coordinates: c = 1/s, std(c) = std(s) / s^2 (first order).
  state_ = mean;
  state_prior_std_ = estimate_.prior_std;
  state_reference_std_ = reference;
  for (int i : {kPinionBearingScale, kGearBearingScale}) {
    state_[i] = 1.0 / mean[i];
    state_prior_std_[i] = estimate_.prior_std[i] / (mean[i] * mean[i]);
    state_reference_std_[i] = reference[i] / (mean[i] * mean[i]);
  }
  state_covariance_ = state_prior_std_.cwiseAbs2().asDiagonal();
  model_error_.reset(state_covariance_);
  covariance_ = estimate_.prior_std.cwiseAbs2().asDiagonal();
  estimate_.value = mean;
  estimate_.std = estimate_.prior_std;
}

CalibrationVector Calibrator::toParameters(const CalibrationVector& state) {
  CalibrationVector p = state;
  p[kPinionBearingScale] = 1.0 / state[kPinionBearingScale];
  p[kGearBearingScale] = 1.0 / state[kGearBearingScale];
  return p;
}

CalibrationMatrix Calibrator::parameterJacobian(const CalibrationVector& state) {
  CalibrationMatrix J = CalibrationMatrix::Identity();
  for (int i : {kPinionBearingScale, kGearBearingScale}) J(i, i) = -1.0 / (state[i] * state[i]);
  return J;
}

CalibrationMatrix Calibrator::filterCovariance() const {
  const CalibrationMatrix J = parameterJacobian(state_);
  return J * state_covariance_ * J.transpose();
}

void Calibrator::interrupt() {
  report_.noteStretch(windows_.openStretch());
  windows_.interrupt();
}

int Calibrator::reading(double t, double pinion, double gear, double phase, double speed,
                        double torque, const StiffnessEstimator& supports,
                        MeasuredTeSample& sample) {
  report_.noteReading();
  const double te = windows_.measuredTe(pinion, gear);
  SteadyStretch dropped;
  const int step = windows_.add(t, pinion, phase, speed, torque, te, supports, model_, dropped);
  if (step & WindowAccumulator::kDropped) report_.noteStretch(dropped);
  int result = kNothing;
  if (step & WindowAccumulator::kSpans) {
    closeWindow(supports);
    windows_.close();
    result |= kWindow;
  }
  if (windows_.sample(te, pinion, phase, torque, estimate_.value, supports, model_, sample))
    result |= kSample;
  return result;
}

void Calibrator::closeWindow(const StiffnessEstimator& supports) {
  ++estimate_.windows;
  const double torque = windows_.meanTorque();
  const double speed = windows_.meanSpeed();
  estimate_.window_torque = torque;
  estimate_.window_speed = speed;
  report_.noteWindow(torque);
  if (estimate_.natural_frequency[0] == 0.0)
    outputs(torque, supports);  // the modes, for the first check
  double value = 0.0, limit = 0.0;
  const WindowOutcome outcome = windows_.fit(speed, estimate_.natural_frequency[0], value, limit);
  if (outcome != WindowOutcome::kUpdated) {
    ++estimate_.not_excited;
    estimate_.outcome = outcome;
    estimate_.excited = false;
    report_.noteOutcome(outcome, value, limit);
    return;
  }
  estimate_.excited = true;
  if (std::abs(torque) <= config_.baseline_torque) {
    windows_.addBaseline(torque, supports, model_);
    ++estimate_.baseline_windows;
    estimate_.baseline = true;
    estimate_.outcome = WindowOutcome::kBaseline;
    report_.noteOutcome(WindowOutcome::kBaseline, std::abs(torque), config_.baseline_torque);
    return;
  }
  if (!windows_.hasBaseline()) {
    ++estimate_.not_excited;
    estimate_.outcome = WindowOutcome::kNoBaseline;
    report_.noteOutcome(WindowOutcome::kNoBaseline, std::abs(torque), config_.baseline_torque);
    return;
  }
  FeatureVector z, z_std;
  windows_.features(torque, supports, model_, z, z_std);
  update(z, z_std, torque);
  outputs(torque, supports);
}

FeatureVector Calibrator::predict(const CalibrationVector& state, double torque) const {
  return windows_.predictFeatures(model_, toParameters(state), torque);
}

void Calibrator::jacobian(const CalibrationVector& p, double torque,
                          ModelErrorScale::FeatureRows& H) const {
  H.setZero();
  // Closed-form columns where the features are simple in the parameter: the offset adds to the
  // mean; a bearing scale s divides its shaft's deflection (d/ds (u/s) = -u/s^2), which is the
  // same at every phase, so it moves the mean only. The mesh scale and T_p by central
  // differences.
  H(0, kTeOffset) = state_prior_std_[kTeOffset] > 0.0 ? 1.0 : 0.0;
  for (int s = 0; s < 2; ++s) {
    const int i = s == 0 ? kPinionBearingScale : kGearBearingScale;
    if (state_prior_std_[i] > 0.0) H(0, i) = windows_.shaftOverBaseline(s);  // mean TE = ... + u c
  }
  for (int i : {kMeshScale, kPreloadTorque}) {
    if (!(state_prior_std_[i] > 0.0)) continue;  // held: no column
    const double step = 1e-4 * std::max(state_prior_std_[i], std::abs(p[i]));
    CalibrationVector a = p, b = p;
    a[i] += step;
    b[i] -= step;
    H.col(i) = (predict(a, torque) - predict(b, torque)) / (2.0 * step);
  }
}

void Calibrator::bound(CalibrationVector& state) {
  // Physical bounds: scales in [0.05, 20) as the YAML loader's, a preload torque >= 0.
  state[kMeshScale] = std::clamp(state[kMeshScale], 0.05, 19.9);
  for (int i : {kPinionBearingScale, kGearBearingScale})
    state[i] = std::clamp(state[i], 1.0 / 19.9, 1.0 / 0.05);
  state[kPreloadTorque] = std::max(0.0, state[kPreloadTorque]);
}

CalibrationVector Calibrator::iteratedUpdate(
    const CalibrationMatrix& prior, const Eigen::Matrix<double, kFeatureSize, kFeatureSize>& R,
    const FeatureVector& z, double torque, ModelErrorScale::FeatureRows& H,
    ModelErrorScale::Gain& K) const {
  // Iterated EKF (Gauss-Newton on the posterior mode): relinearise at the new estimate.
  CalibrationVector theta = state_;
  for (int iteration = 0; iteration < 4; ++iteration) {
    const FeatureVector h = predict(theta, torque);
    if (iteration > 0) jacobian(theta, torque, H);
    const Eigen::Matrix<double, kFeatureSize, kFeatureSize> Si = H * prior * H.transpose() + R;
    K = prior * H.transpose() * Si.inverse();
    CalibrationVector next = state_ + K * (z - h - H * (state_ - theta));
    bound(next);
    const double moved =
        ((next - theta).cwiseQuotient(state_prior_std_.cwiseMax(1e-300))).cwiseAbs().maxCoeff();
    theta = next;
    if (moved < 1e-6) break;
  }
  return theta;
}

CalibrationMatrix Calibrator::processNoise(double t) const {
  const double dt = has_update_t_ ? std::max(0.0, t - last_update_t_) : 0.0;
  const CalibrationVector walk = (state_prior_std_.array() > 0.0).select(state_reference_std_, 0.0);
  return ((config_.drift * config_.drift * dt) * walk.cwiseAbs2()).asDiagonal();
}

void Calibrator::update(const FeatureVector& z, const FeatureVector& z_std, double torque) {
  // Random walk since the last update (a preload that relaxes, wear): relative to the drawing's
  // spread (the prior's, unless a calibrated gearbox keeps the drawing's as reference_std). Held
  // parameters (prior std 0) do not walk.
  const double t = windows_.endTime();
  const CalibrationMatrix Q = processNoise(t);
  const CalibrationMatrix prior = state_covariance_ + Q;

  // Measurement noise: the window's own, the relative model error and the floor
  // (docs/calibration.md). The model error repeats at an operating point: the n-th window there
  // carries n times its variance, so a long dwell adds no more than one window's worth of model
  // information. N (the fit's, the baseline's and the floor's variance) and M (the model error)
  // apart, for model_error_ (model_error_scale.hpp).
  Eigen::Matrix<double, kFeatureSize, kFeatureSize> R =
      Eigen::Matrix<double, kFeatureSize, kFeatureSize>::Zero();
  const FeatureVector h0 = predict(state_, torque);
  const double repeats = static_cast<double>(windows_.countAtOperatingPoint(torque));
  FeatureVector noise, model_variance;
  for (int i = 0; i < kFeatureSize; ++i) {
    const double model = config_.model_error * std::abs(h0[i]);
    noise[i] = z_std[i] * z_std[i] + config_.te_noise_floor * config_.te_noise_floor;
    model_variance[i] = repeats * model * model;
    // Summed in the order R always was, not as noise + model_variance: the same bits as before.
    R(i, i) =
        z_std[i] * z_std[i] + model_variance[i] + config_.te_noise_floor * config_.te_noise_floor;
  }
  ModelErrorScale::FeatureRows H;
  jacobian(state_, torque, H);
  const FeatureVector innovation = z - h0;
  const Eigen::Matrix<double, kFeatureSize, kFeatureSize> S = H * prior * H.transpose() + R;
  const double nis = innovation.dot(S.ldlt().solve(innovation));
  estimate_.nis = nis;
  estimate_.measured = z;
  estimate_.feature_std = R.diagonal().cwiseSqrt();
  if (!(nis <= config_.gate)) {  // also refuses a NaN
    ++estimate_.gated;
    estimate_.outcome = WindowOutcome::kGated;
    estimate_.predicted = h0;
    report_.noteOutcome(WindowOutcome::kGated, nis, config_.gate);
    return;
  }
  model_error_.predict(Q);
  const FeatureVector variance =
      model_error_.innovationVariance(H, noise);  // before the update, at the prior's H
  ModelErrorScale::Gain K;
  const CalibrationVector theta = iteratedUpdate(prior, R, z, torque, H, K);
  // Joseph form: stays symmetric positive semi-definite whatever the rounding.
  const CalibrationMatrix IKH = CalibrationMatrix::Identity() - K * H;
  state_covariance_ = IKH * prior * IKH.transpose() + K * R * K.transpose();
  state_covariance_ = 0.5 * (state_covariance_ + state_covariance_.transpose()).eval();
  model_error_.update(innovation, variance, noise, model_variance, K, H);
  state_ = theta;
  last_update_t_ = t;
  has_update_t_ = true;
  ++estimate_.updates;
  estimate_.outcome = WindowOutcome::kUpdated;
  report_.noteOutcome(WindowOutcome::kUpdated, nis, config_.gate);
  estimate_.predicted = predict(state_, torque);
}

// ---- Natural frequencies (docs/calibration.md "Natural frequencies") ----

namespace {

/// Upper 0.1 % points of the chi-square distribution with 1, 2 and 3 degrees of freedom
/// (NIST/SEMATECH e-Handbook of Statistical Methods, sec. 1.3.6.7.4, "Critical values of the
/// chi-square distribution", column 0.999).
constexpr double kChiSquare999[3] = {10.828, 13.816, 16.266};

/// The mass-weighted modal assurance criterion (a'Mb)^2 / (a'Ma b'Mb), M = diag(mass) (Allemang &
/// Brown 1982, with the mass as the weighting): 1 or 0 between two modes of one model, which are
/// M-orthogonal.
double mac(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& mass) {
  const Eigen::Vector3d ma = mass.cwiseProduct(a);
  const double ab = ma.dot(b), aa = ma.dot(a), bb = b.dot(mass.cwiseProduct(b));
  return aa > 0.0 && bb > 0.0 ? ab * ab / (aa * bb) : 0.0;
}

/// For each mode of `from`, the mode of `to` it becomes: the one-to-one assignment of the highest
/// total MAC over the six permutations; ties keep the order by frequency.
std::array<int, 3> followModes(const std::array<Mode, 3>& from, const std::array<Mode, 3>& to,
                               const Eigen::Vector3d& mass) {
  std::array<int, 3> order{0, 1, 2}, best = order;
  double best_sum = -1.0;
  do {
    double sum = 0.0;
    for (int k = 0; k < 3; ++k) sum += mac(from[k].shape, to[order[k]].shape, mass);
    if (sum > best_sum + 1e-12) {
      best_sum = sum;
      best = order;
    }
  } while (std::next_permutation(order.begin(), order.end()));
  return best;
}

/// Gauss-Newton relinearisations of one record of natural frequencies at most: near a veering the
/// cost falls slowly (a record of the validation's rig 44 still lowered it at the sixth) [-].
constexpr int kModalIterations = 8;

[[noreturn]] void invalidFrequency(std::size_t i, const char* field, double value,
                                   const char* why) {
  throwInvalid("calibration: natural frequencies[" + std::to_string(i) + "]." + field, value, why);
}

}  // namespace

WindowOutcome Calibrator::modalUpdate(double t, const ModalFrequency* frequencies,
                                      std::size_t count, double torque,
                                      const StiffnessEstimator& supports) {
  using Rows = Eigen::Matrix<double, 3, kCalibrationSize>;
  using Gain = Eigen::Matrix<double, kCalibrationSize, 3>;
  if (count > 3) {
    throwInvalid("calibration: natural frequencies count", static_cast<double>(count),
                 "at most 3, one per mode of the model");
  }
  if (count > 0 && frequencies == nullptr) throw std::invalid_argument("modalUpdate: no array");
  requireFinite("calibration: natural frequencies torque", torque);
  requireFinite("calibration: natural frequencies t", t);
  std::array<int, 3> mode{};
  Eigen::Vector3d z = Eigen::Vector3d::Zero(), z_std = Eigen::Vector3d::Ones();
  for (std::size_t j = 0; j < count; ++j) {
    const ModalFrequency& f = frequencies[j];
    if (f.mode < 0 || f.mode > 2) {
      invalidFrequency(j, "mode", f.mode, "must be 0, 1 or 2 (the model's modes by frequency)");
    }
    for (std::size_t i = 0; i < j; ++i) {
      if (mode[i] == f.mode) invalidFrequency(j, "mode", f.mode, "appears twice in one record");
    }
    if (!(std::isfinite(f.frequency) && f.frequency > 0.0))
      invalidFrequency(j, "frequency", f.frequency, "must be positive and finite [Hz]");
    if (!(std::isfinite(f.frequency_std) && f.frequency_std > 0.0))
      invalidFrequency(j, "frequency_std", f.frequency_std, "must be positive and finite [Hz]");
    mode[j] = f.mode;
    z[j] = f.frequency;
    z_std[j] = f.frequency_std;
  }
  if (count == 0) return WindowOutcome::kNone;

  // h(state): the matched modes' natural frequencies of the model at this torque, with the
  // supports' unit stiffness at their current load (as bands() and modes()); slots past `count`
  // stay 0. Mode k is the current estimate's k-th by frequency (modes()); at another state it is
  // followed by its shape (the assignment of highest total MAC), so that two modes that change
  // order within the update keep their identities.
  const std::array<double, 2> unit = unitBearingStiffness(supports);
  const std::array<Mode, 3> reference = modesAt(estimate_.value, torque, unit, supports);
  const GearRotorParameters rotor = rigRotorParameters(*rig_, supports.mesh(), unit);
  const Eigen::Vector3d mass(rotor.pinion_mass, rotor.gear_mass, rotor.equivalentMass());
  auto predictModes = [&](const CalibrationVector& state) {
    const std::array<Mode, 3> m = modesAt(toParameters(state), torque, unit, supports);
    const std::array<int, 3> follow = followModes(reference, m, mass);
    Eigen::Vector3d h = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < count; ++j)
      h[j] =
          m[static_cast<std::size_t>(follow[static_cast<std::size_t>(mode[j])])].natural_frequency;
    return h;
  };
  // The Jacobian by central differences on the state, as jacobian() for the mesh scale and T_p;
  // the TE offset does not enter the modes, a held parameter has no column.
  auto modalJacobian = [&](const CalibrationVector& state, Rows& H) {
    H.setZero();
    for (int i : {kMeshScale, kPinionBearingScale, kGearBearingScale, kPreloadTorque}) {
      if (!(state_prior_std_[i] > 0.0)) continue;
      const double step = 1e-4 * std::max(state_prior_std_[i], std::abs(state[i]));
      CalibrationVector a = state, b = state;
      a[i] += step;
      b[i] -= step;
      H.col(i) = (predictModes(a) - predictModes(b)) / (2.0 * step);
    }
  };

  const CalibrationMatrix Q = processNoise(t);
  const CalibrationMatrix prior = state_covariance_ + Q;
  const Eigen::Vector3d h0 = predictModes(state_);
  Rows H;
  modalJacobian(state_, H);
  // No parameter that moves these modes is estimated: nothing to learn from the record.
  if (H.cwiseAbs().maxCoeff() == 0.0) return WindowOutcome::kNone;
  // Measurement noise: the identification's variance and the relative model error of a natural
  // frequency (masses, inertias, the housing), which every record of the same mode shares: the
  // n-th record of a mode carries n times its variance. Unused slots: unit variance, no row.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (std::size_t j = 0; j < count; ++j) {
    const double repeats = static_cast<double>(modal_count_[static_cast<std::size_t>(mode[j])] + 1);
    const double model = config_.modal_model_error * h0[j];
    R(j, j) = z_std[j] * z_std[j] + repeats * model * model;
  }
  const Eigen::Vector3d innovation = z - h0;
  const Eigen::Matrix3d S = H * prior * H.transpose() + R;
  const double nis = innovation.dot(S.ldlt().solve(innovation));
  estimate_.modal_nis = nis;
  if (!(nis <= kChiSquare999[count - 1])) {  // also refuses a NaN
    ++estimate_.modal_gated;
    return WindowOutcome::kGated;
  }
  // Iterated EKF, as iteratedUpdate: Gauss-Newton on the posterior mode, the frequencies being
  // nonlinear in the state (f ~ sqrt(k), k ~ 1/c). A step is taken only where it lowers the
  // posterior's cost (prior term plus the frequencies' residual), halved up to 6 times otherwise
  // (backtracking line search, Nocedal & Wright 2006, Algorithm 3.1): near a veering the
  // frequencies bend sharply and a full step can overshoot. A first step that finds no lower cost
  // gates the record: the model cannot follow it from the estimate.
  CalibrationMatrix prior_held = prior;  // the prior term over the estimated parameters only
  for (int i = 0; i < kCalibrationSize; ++i)
    if (!(state_prior_std_[i] > 0.0)) {
      prior_held.row(i).setZero();
      prior_held.col(i).setZero();
      prior_held(i, i) = 1.0;
    }
  const Eigen::LDLT<CalibrationMatrix> prior_ldlt(prior_held);
  auto cost = [&](const CalibrationVector& state, const Eigen::Vector3d& h) {
    const CalibrationVector d = state - state_;
    double c = d.dot(prior_ldlt.solve(d));
    for (std::size_t j = 0; j < count; ++j) c += (z[j] - h[j]) * (z[j] - h[j]) / R(j, j);
    return c;
  };
  CalibrationVector theta = state_;
  Eigen::Vector3d h = h0;
  double current = cost(theta, h);
  Gain K;
  for (int iteration = 0; iteration < kModalIterations; ++iteration) {
    if (iteration > 0) modalJacobian(theta, H);
    const Eigen::Matrix3d Si = H * prior * H.transpose() + R;
    K = prior * H.transpose() * Si.inverse();
    CalibrationVector next = state_ + K * (z - h - H * (state_ - theta));
    bound(next);
    Eigen::Vector3d h_next = predictModes(next);
    double next_cost = cost(next, h_next);
    const CalibrationVector step = next - theta;
    for (int halving = 1; halving <= 6 && !(next_cost <= current); ++halving) {
      next = theta + std::ldexp(1.0, -halving) * step;
      bound(next);
      h_next = predictModes(next);
      next_cost = cost(next, h_next);
    }
    if (!(next_cost <= current)) {
      if (iteration > 0) break;
      ++estimate_.modal_gated;
      return WindowOutcome::kGated;
    }
    const double moved =
        ((next - theta).cwiseQuotient(state_prior_std_.cwiseMax(1e-300))).cwiseAbs().maxCoeff();
    theta = next;
    h = h_next;
    current = next_cost;
    if (moved < 1e-6) break;
  }
  // Joseph form, and the same gain and noise on the model-error scaling's covariance: the
  // frequencies carry no allowance of the TE features, so their information stays whatever c.
  const CalibrationMatrix IKH = CalibrationMatrix::Identity() - K * H;
  const CalibrationMatrix KRK = K * R * K.transpose();
  state_covariance_ = IKH * prior * IKH.transpose() + KRK;
  state_covariance_ = 0.5 * (state_covariance_ + state_covariance_.transpose()).eval();
  model_error_.predict(Q);
  model_error_.absorb(IKH, KRK);
  state_ = theta;
  last_update_t_ = has_update_t_ ? std::max(last_update_t_, t) : t;
  has_update_t_ = true;
  for (std::size_t j = 0; j < count; ++j) ++modal_count_[static_cast<std::size_t>(mode[j])];
  ++estimate_.modal_updates;
  outputs(torque, supports);
  return WindowOutcome::kUpdated;
}

template <typename F>
double Calibrator::spreadOf(F&& f, std::uint32_t depends_on) const {
  // A scalar output's standard deviation by linearisation: sqrt(g' P g), g by central differences.
  // A parameter the output does not read has g_i = (f(a) - f(b)) / 2h = 0 exactly: skipping it
  // changes no bit and saves two evaluations.
  const CalibrationVector& theta = estimate_.value;
  CalibrationVector g = CalibrationVector::Zero();
  for (int i = 0; i < kCalibrationSize; ++i) {
    if (!(estimate_.prior_std[i] > 0.0) || !(depends_on & (1u << i))) continue;
    const double step = 1e-4 * std::max(estimate_.prior_std[i], std::abs(theta[i]));
    CalibrationVector a = theta, b = theta;
    a[i] += step;
    b[i] -= step;
    g[i] = (f(a) - f(b)) / (2.0 * step);
  }
  return std::sqrt(std::max(0.0, g.dot(covariance_ * g)));
}

std::array<double, 2> Calibrator::unitBearingStiffness(const StiffnessEstimator& supports) const {
  std::array<double, 2> unit{0.0, 0.0};
  for (std::size_t i = 0; i < rig_->bearings.size(); ++i) {
    const SupportEstimate& s = supports.current().supports[i];
    unit[rig_->bearings[i].shaft] +=
        s.solution.radialStiffness() / supports.supportConfig(i).stiffness_scale;
  }
  return unit;
}

std::array<Mode, 3> Calibrator::modesAt(const CalibrationVector& p, double torque,
                                        const std::array<double, 2>& unit,
                                        const StiffnessEstimator& supports) const {
  const std::array<double, 2> kb{p[kPinionBearingScale] * unit[0], p[kGearBearingScale] * unit[1]};
  return modalAnalysis(rigRotorParameters(*rig_, supports.mesh(), kb),
                       model_.meanMeshStiffness(p, torque));
}

std::array<Mode, 3> Calibrator::modes(double torque, const StiffnessEstimator& supports) const {
  return modesAt(estimate_.value, torque, unitBearingStiffness(supports), supports);
}

CalibrationBands Calibrator::bands(double torque, const StiffnessEstimator& supports,
                                   bool with_modes) const {
  CalibrationBands out;
  out.calibrated = estimate_.updates > 0 || estimate_.modal_updates > 0;
  const CalibrationVector& theta = estimate_.value;
  const CalibrationMatrix& P = covariance_;
  // Period-mean mesh stiffness at this torque (its flank state per phase).
  auto mesh = [&](const CalibrationVector& p) { return model_.meanMeshStiffness(p, torque); };
  out.mesh_stiffness = mesh(theta);
  // StaticTeModel::meanMeshStiffness reads the mesh scale and the preload torque only (the flank
  // states and k1, k_c): per stiffness message (1 kHz) five evaluations instead of eleven.
  const double mesh_std = spreadOf(mesh, (1u << kMeshScale) | (1u << kPreloadTorque));
  out.mesh_stiffness_low = out.mesh_stiffness - k95 * mesh_std;
  out.mesh_stiffness_high = out.mesh_stiffness + k95 * mesh_std;
  // Bearing stiffness per shaft: the Hertz tangent at the current load (scale 1) times the scale.
  const std::array<double, 2> unit = unitBearingStiffness(supports);
  for (int s = 0; s < 2; ++s) {
    const int index = s == 0 ? kPinionBearingScale : kGearBearingScale;
    out.bearing_stiffness[s] = theta[index] * unit[s];
    out.bearing_stiffness_low[s] = (theta[index] - k95 * estimate_.std[index]) * unit[s];
    out.bearing_stiffness_high[s] = (theta[index] + k95 * estimate_.std[index]) * unit[s];
  }
  if (!with_modes) return out;
  // Natural frequencies of the calibrated model (modal_analysis.hpp), each with its band.
  auto modes = [&](const CalibrationVector& p) { return modesAt(p, torque, unit, supports); };
  const std::array<Mode, 3> m = modes(theta);
  // The three frequencies' gradients together: two modal analyses per parameter that moves them.
  Eigen::Matrix<double, 3, kCalibrationSize> G = Eigen::Matrix<double, 3, kCalibrationSize>::Zero();
  for (int i : {kMeshScale, kPinionBearingScale, kGearBearingScale, kPreloadTorque}) {
    if (!(estimate_.prior_std[i] > 0.0)) continue;
    const double step = 1e-4 * std::max(estimate_.prior_std[i], std::abs(theta[i]));
    CalibrationVector a = theta, b = theta;
    a[i] += step;
    b[i] -= step;
    const std::array<Mode, 3> ma = modes(a), mb = modes(b);
    for (int k = 0; k < 3; ++k)
      G(k, i) = (ma[k].natural_frequency - mb[k].natural_frequency) / (2.0 * step);
  }
  const Eigen::Matrix3d frequency_covariance = G * P * G.transpose();
  for (int i = 0; i < 3; ++i) {
    const double f = m[i].natural_frequency;
    const double s = std::sqrt(std::max(0.0, frequency_covariance(i, i)));
    out.natural_frequency[i] = f;
    out.natural_frequency_low[i] = f - k95 * s;
    out.natural_frequency_high[i] = f + k95 * s;
  }
  return out;
}

void Calibrator::outputs(double torque, const StiffnessEstimator& supports) {
  CalibrationEstimate& e = estimate_;
  // The parameters and their covariance from the state's (first order in c -> 1/c).
  // The reported covariance: the filter's own while the windows show a model error within the
  // configured allowance; widened to the estimate's real covariance under the model error they
  // show where it exceeds it (model_error_scale.hpp). Never narrowed: a model error that repeats
  // at an operating point is invisible in the innovations, and bands learned down from them were
  // overconfident after a 10-min dwell at one load (docs/calibration.md, section 3).
  const CalibrationVector theta = toParameters(state_);
  const CalibrationMatrix J = parameterJacobian(state_);
  e.model_error_scale = model_error_.scale();
  const bool wider = (e.model_error_scale.array() > 1.0).any();
  const CalibrationMatrix P = wider ? model_error_.covariance(1.0) : state_covariance_;
  covariance_ = J * P * J.transpose();
  e.value = theta;
  e.std = covariance_.diagonal().cwiseMax(0.0).cwiseSqrt();
  // Identified: the data have at least tripled the drawing's information (std below half the
  // drawing's spread: the prior's, or a calibrated gearbox's reference_std), judged in the state's
  // coordinates, where the measurement is linear in the bearing factors: the
  // scale's std also shrinks as s^2 when the estimate falls, which is not information. On the
  // reported covariance: information the windows seem to give but their model error takes back
  // (c > 1) does not count.
  for (int i = 0; i < kCalibrationSize; ++i) {
    e.identified[i] = state_prior_std_[i] > 0.0 &&
                      std::sqrt(std::max(0.0, P(i, i))) < 0.5 * state_reference_std_[i];
  }
  // Series compliance at the reference torque: mean TE above zero torque over the mesh force.
  const double tr = config_.reference_torque;
  model_.shaftDeflection(tr, supports, scratch_);
  const std::array<double, 2> zero{0.0, 0.0};
  const double fr = model_.meshForce(tr);
  auto compliance = [&](const CalibrationVector& p) {
    return (model_.features(p, tr, scratch_, 0.0, zero)[0] - p[kTeOffset]) / fr;
  };
  e.series_compliance = compliance(theta);
  e.series_compliance_std = spreadOf(compliance);
  // Stiffness and natural frequencies at the window's torque, with their bands.
  const CalibrationBands b = bands(torque, supports, true);
  e.mesh_stiffness = b.mesh_stiffness;
  e.mesh_stiffness_low = b.mesh_stiffness_low;
  e.mesh_stiffness_high = b.mesh_stiffness_high;
  e.bearing_stiffness = b.bearing_stiffness;
  e.bearing_stiffness_low = b.bearing_stiffness_low;
  e.bearing_stiffness_high = b.bearing_stiffness_high;
  e.natural_frequency = b.natural_frequency;
  e.natural_frequency_low = b.natural_frequency_low;
  e.natural_frequency_high = b.natural_frequency_high;
  e.knee_torque = model_.kneeTorque(theta);
}

CalibrationProgress Calibrator::progress() const {
  return report_.progress(windows_.openStretch());
}

std::string Calibrator::waitingReason() const {
  return report_.waitingReason(estimate_, windows_.openStretch());
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/calibration/calibrator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

namespace {

constexpr double k95 = 1.959963984540054;  // two-sided 95 % of the normal distribution

const RigConfig& required(const std::shared_ptr<const RigConfig>& rig) {
  if (!rig) throw std::invalid_argument("Calibrator: no rig");  // a caller's bug, not bad data
  return *rig;
}

/// The calibration block's prior means.
CalibrationVector priorMean(const CalibrationConfig& c) {
  CalibrationVector mean;
  mean << c.mesh_stiffness_scale.mean, c.pinion_bearing_scale.mean, c.gear_bearing_scale.mean,
      c.preload_torque.mean, c.te_offset.mean;
  return mean;
}

/// The calibration block's prior std, or (`reference`) the drawing's spread; T_p is held on a rig
/// without a scissor spring.
CalibrationVector priorStd(const RigConfig& rig, bool reference) {
  const CalibrationConfig& c = rig.calibration;
  CalibrationVector std;
  if (reference) {
    std << c.mesh_stiffness_scale.reference(), c.pinion_bearing_scale.reference(),
        c.gear_bearing_scale.reference(), c.preload_torque.reference(), c.te_offset.reference();
  } else {
    std << c.mesh_stiffness_scale.std, c.pinion_bearing_scale.std, c.gear_bearing_scale.std,
        c.preload_torque.std, c.te_offset.std;
  }
  if (!(rig.anti_backlash.spring_stiffness > 0.0)) std[kPreloadTorque] = 0.0;  // no scissor spring
  return std;
}

/// Each shaft's bearing stiffness at scale 1 [N/m]: the supports' radial stiffness at their
/// current load over their configured stiffness_scale.
std::array<double, 2> unitBearingStiffness(const RigConfig& rig,
                                           const StiffnessEstimator& supports) {
  std::array<double, 2> unit{0.0, 0.0};
  for (std::size_t i = 0; i < rig.bearings.size(); ++i) {
    const SupportEstimate& s = supports.current().supports[i];
    unit[rig.bearings[i].shaft] +=
        s.solution.radialStiffness() / supports.supportConfig(i).stiffness_scale;
  }
  return unit;
}

/// The model's modes at parameters p, pinion torque [N·m] and unit bearing stiffness [N/m].
std::array<Mode, 3> modesAt(const RigConfig& rig, const StaticTeModel& model,
                            const CalibrationVector& p, double torque,
                            const std::array<double, 2>& unit, const StiffnessEstimator& supports) {
  const std::array<double, 2> kb{p[kPinionBearingScale] * unit[0], p[kGearBearingScale] * unit[1]};
  return modalAnalysis(rigRotorParameters(rig, supports.mesh(), kb),
                       model.meanMeshStiffness(p, torque));
}

}  // namespace

Calibrator::Calibrator(const RigConfig& rig) : Calibrator(std::make_shared<const RigConfig>(rig)) {}

Calibrator::Calibrator(std::shared_ptr<const RigConfig> shared_rig,
                       std::shared_ptr<const AntiBacklashMesh> mesh)
    : rig_(std::move(shared_rig)),
      config_(required(rig_).calibration),
      model_(*rig_, std::move(mesh)),
      windows_(*rig_, model_),
      estimator_(config_, priorMean(config_), priorStd(*rig_, false), priorStd(*rig_, true)),
      report_(windows_.windowAngle(), config_.baseline_torque) {
  const RigConfig& rig = *rig_;
  if (!config_.present) throw InvalidInput("calibration: the gearbox has no calibration block");
  if (!rig.dynamics.present)
    throw InvalidInput("calibration: needs the gearbox's dynamics block (masses for the modes)");
  estimate_.prior_std = priorStd(rig, false);
  covariance_ = estimate_.prior_std.cwiseAbs2().asDiagonal();
  estimate_.value = priorMean(config_);
  estimate_.std = estimate_.prior_std;
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

namespace {

/// A window's TE features as the filter's measurement: the model on the window's sampled phases.
class TeFeatures final : public StateMeasurement {
 public:
  /// The features of the last window `windows` prepared, at torque [N·m].
  TeFeatures(const WindowAccumulator& windows, const StaticTeModel& model,
             const CalibrationVector& prior_std, double torque)
      : windows_(windows), model_(model), prior_std_(prior_std), torque_(torque) {}

  /// The features at a state.
  MeasurementVector predict(const CalibrationVector& state) const override {
    return windows_.predictFeatures(model_, CalibrationEstimator::toParameters(state), torque_);
  }

  /// The features' Jacobian at state p: closed-form columns for the offset and the bearing
  /// compliances, central differences for the mesh scale and T_p; held parameters 0.
  void jacobian(const CalibrationVector& p, MeasurementRows& H) const override {
    H.setZero();
    // Closed-form columns where the features are simple in the parameter: the offset adds to the
    // mean; a bearing scale s divides its shaft's deflection (d/ds (u/s) = -u/s^2), which is the
    // same at every phase, so it moves the mean only. The mesh scale and T_p by central
    // differences.
    H(0, kTeOffset) = prior_std_[kTeOffset] > 0.0 ? 1.0 : 0.0;
    for (int s = 0; s < 2; ++s) {
      const int i = s == 0 ? kPinionBearingScale : kGearBearingScale;
      if (prior_std_[i] > 0.0) H(0, i) = windows_.shaftOverBaseline(s);  // mean TE = ... + u c
    }
    for (int i : {kMeshScale, kPreloadTorque}) {
      if (!(prior_std_[i] > 0.0)) continue;  // held: no column
      const double step = 1e-4 * std::max(prior_std_[i], std::abs(p[i]));
      CalibrationVector a = p, b = p;
      a[i] += step;
      b[i] -= step;
      H.col(i) = (predict(a) - predict(b)) / (2.0 * step);
    }
  }

 private:
  const WindowAccumulator& windows_;
  const StaticTeModel& model_;
  const CalibrationVector& prior_std_;
  double torque_;
};

}  // namespace

void Calibrator::update(const FeatureVector& z, const FeatureVector& z_std, double torque) {
  const TeFeatures features(windows_, model_, estimator_.priorStd(), torque);
  const double repeats = static_cast<double>(windows_.countAtOperatingPoint(torque));
  FeatureUpdate u;
  const bool updated =
      estimator_.updateFeatures(features, z, z_std, windows_.endTime(), repeats, u);
  estimate_.nis = u.nis;
  estimate_.measured = z;
  estimate_.feature_std = u.feature_std;
  if (!updated) {
    ++estimate_.gated;
    estimate_.outcome = WindowOutcome::kGated;
    estimate_.predicted = u.predicted;
    report_.noteOutcome(WindowOutcome::kGated, u.nis, config_.gate);
    return;
  }
  ++estimate_.updates;
  estimate_.outcome = WindowOutcome::kUpdated;
  report_.noteOutcome(WindowOutcome::kUpdated, u.nis, config_.gate);
  estimate_.predicted = features.predict(estimator_.state());
}

// ---- Natural frequencies (docs/calibration.md "Natural frequencies") ----

namespace {

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

[[noreturn]] void invalidFrequency(std::size_t i, const char* field, double value,
                                   const char* why) {
  throwInvalid("calibration: natural frequencies[" + std::to_string(i) + "]." + field, value, why);
}

/// A record's natural frequencies as the filter's measurement: the matched modes' natural
/// frequencies of the model at the record's torque, with the supports' unit stiffness at their
/// current load (as bands() and modes()); slots past `count` stay 0. Mode k is the estimate's k-th
/// by frequency (modes()); at another state it is followed by its shape (the assignment of highest
/// total MAC), so that two modes that change order within the update keep their identities.
class ModalFrequencies final : public StateMeasurement {
 public:
  /// The modes `mode` (count of them) at torque [N·m], numbered at the parameters `estimate`.
  ModalFrequencies(const RigConfig& rig, const StaticTeModel& model,
                   const StiffnessEstimator& supports, const CalibrationVector& estimate,
                   const CalibrationVector& prior_std, double torque,
                   const std::array<int, 3>& mode, std::size_t count)
      : rig_(rig),
        model_(model),
        supports_(supports),
        prior_std_(prior_std),
        torque_(torque),
        mode_(mode),
        count_(count),
        unit_(unitBearingStiffness(rig, supports)),
        reference_(modesAt(rig, model, estimate, torque, unit_, supports)) {
    const GearRotorParameters rotor = rigRotorParameters(rig, supports.mesh(), unit_);
    mass_ = Eigen::Vector3d(rotor.pinion_mass, rotor.gear_mass, rotor.equivalentMass());
  }

  /// The matched modes' natural frequencies [Hz] at a state.
  MeasurementVector predict(const CalibrationVector& state) const override {
    const std::array<Mode, 3> m =
        modesAt(rig_, model_, CalibrationEstimator::toParameters(state), torque_, unit_, supports_);
    const std::array<int, 3> follow = followModes(reference_, m, mass_);
    Eigen::Vector3d h = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < count_; ++j)
      h[j] =
          m[static_cast<std::size_t>(follow[static_cast<std::size_t>(mode_[j])])].natural_frequency;
    return h;
  }

  /// The Jacobian by central differences on the state, as TeFeatures's for the mesh scale and T_p;
  /// the TE offset does not enter the modes, a held parameter has no column.
  void jacobian(const CalibrationVector& state, MeasurementRows& H) const override {
    H.setZero();
    for (int i : {kMeshScale, kPinionBearingScale, kGearBearingScale, kPreloadTorque}) {
      if (!(prior_std_[i] > 0.0)) continue;
      const double step = 1e-4 * std::max(prior_std_[i], std::abs(state[i]));
      CalibrationVector a = state, b = state;
      a[i] += step;
      b[i] -= step;
      H.col(i) = (predict(a) - predict(b)) / (2.0 * step);
    }
  }

 private:
  const RigConfig& rig_;
  const StaticTeModel& model_;
  const StiffnessEstimator& supports_;
  const CalibrationVector& prior_std_;
  double torque_;
  const std::array<int, 3>& mode_;
  std::size_t count_;
  std::array<double, 2> unit_;
  std::array<Mode, 3> reference_;
  Eigen::Vector3d mass_;
};

}  // namespace

WindowOutcome Calibrator::modalUpdate(double t, const ModalFrequency* frequencies,
                                      std::size_t count, double torque,
                                      const StiffnessEstimator& supports) {
  if (count > 3) {
    throwInvalid("calibration: natural frequencies count", static_cast<double>(count),
                 "at most 3, one per mode of the model");
  }
  if (count > 0 && frequencies == nullptr) throw std::invalid_argument("modalUpdate: no array");
  requireFinite("calibration: natural frequencies torque", torque);
  requireFinite("calibration: natural frequencies t", t);
  std::array<int, 3> mode{};
  MeasurementVector z = MeasurementVector::Zero(), z_std = MeasurementVector::Ones();
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

  const ModalFrequencies modes(*rig_, model_, supports, estimate_.value, estimator_.priorStd(),
                               torque, mode, count);
  double nis = 0.0;
  const WindowOutcome outcome = estimator_.updateFrequencies(modes, z, z_std, mode, count, t, nis);
  if (outcome == WindowOutcome::kNone) return outcome;
  estimate_.modal_nis = nis;
  if (outcome == WindowOutcome::kGated) {
    ++estimate_.modal_gated;
    return outcome;
  }
  ++estimate_.modal_updates;
  outputs(torque, supports);
  return outcome;
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

std::array<Mode, 3> Calibrator::modes(double torque, const StiffnessEstimator& supports) const {
  return modesAt(*rig_, model_, estimate_.value, torque, unitBearingStiffness(*rig_, supports),
                 supports);
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
  const std::array<double, 2> unit = unitBearingStiffness(*rig_, supports);
  for (int s = 0; s < 2; ++s) {
    const int index = s == 0 ? kPinionBearingScale : kGearBearingScale;
    out.bearing_stiffness[s] = theta[index] * unit[s];
    out.bearing_stiffness_low[s] = (theta[index] - k95 * estimate_.std[index]) * unit[s];
    out.bearing_stiffness_high[s] = (theta[index] + k95 * estimate_.std[index]) * unit[s];
  }
  if (!with_modes) return out;
  // Natural frequencies of the calibrated model (modal_analysis.hpp), each with its band.
  auto modes = [&](const CalibrationVector& p) {
    return modesAt(*rig_, model_, p, torque, unit, supports);
  };
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
  // at an operating point is invisible in the innovations, and bands learned down from them are
  // overconfident after a 10-min dwell at one load (docs/calibration.md, section 3).
  const CalibrationVector& state = estimator_.state();
  const CalibrationVector theta = CalibrationEstimator::toParameters(state);
  const CalibrationMatrix J = CalibrationEstimator::parameterJacobian(state);
  e.model_error_scale = estimator_.modelError().scale();
  const bool wider = (e.model_error_scale.array() > 1.0).any();
  const CalibrationMatrix P =
      wider ? estimator_.modelError().covariance(1.0) : estimator_.stateCovariance();
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
    e.identified[i] = estimator_.priorStd()[i] > 0.0 &&
                      std::sqrt(std::max(0.0, P(i, i))) < 0.5 * estimator_.referenceStd()[i];
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

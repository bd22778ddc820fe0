#include "drivetrain_stiffness/calibration/window_accumulator.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {

WindowAccumulator::WindowAccumulator(const RigConfig& rig, const StaticTeModel& model)
    : config_(rig.calibration),
      regression_(rig.gears.teeth[0], rig.gears.teeth[1]),
      base_radius_(model.baseRadius()),
      pinion_teeth_(rig.gears.teeth[0]) {
  const int teeth[2] = {rig.gears.teeth[0], rig.gears.teeth[1]};
  // Whole turns of both encoders shift x by 2 pi (m r_b,p + n r_b,g); with r_b proportional to z
  // these form the lattice 2 pi r_b,p gcd(z_p, z_g) / z_p.
  lattice_ = kTwoPi * base_radius_[0] * std::gcd(teeth[0], teeth[1]) / teeth[0];
  gear_turn_ = kTwoPi * std::max(1.0, static_cast<double>(teeth[1]) / teeth[0]);
}

double WindowAccumulator::measuredTe(double pinion, double gear) {
  // 1. The measured TE, reduced onto the lattice around the first one.
  const double raw = base_radius_[0] * pinion + base_radius_[1] * gear;
  if (!te_reference_) te_reference_ = raw;
  return *te_reference_ + std::remainder(raw - *te_reference_, lattice_);
}

int WindowAccumulator::add(double t, double pinion, double phase, double speed, double torque,
                           double te, const StiffnessEstimator& supports, StaticTeModel& model,
                           SteadyStretch& dropped) {
  // 2. The window: closed when it spans a gear turn, dropped when the filtered torque leaves its
  // band (first-order low-pass, exact for the time step).
  if (!filtered_torque_ || !(t > last_t_)) {
    filtered_torque_ = filtered_torque_ ? *filtered_torque_ : torque;
  } else {
    *filtered_torque_ += (torque - *filtered_torque_) * -std::expm1(-(t - last_t_) / kTorqueFilter);
  }
  last_t_ = t;
  const double watched = *filtered_torque_;
  int result = kNothing;
  if (window_.open && !inBand(watched)) {
    dropped = openStretch();
    result |= kDropped;
    window_.open = false;
  }
  if (!window_.open) {
    regression_.clear();
    window_ = Window{};
    histogram_.clear();
    window_.open = true;
    window_.t0 = t;
    window_.torque0 = watched;
    window_.angle_min = window_.angle_max = pinion;
    model.shaftDeflection(watched, supports, window_.shafts);
  }
  if (!model.nearSwitch(phase, kSwitchGuard)) {
    histogram_.add(phase);
    regression_.add(pinion, phase, te);
  }
  window_.t1 = t;
  window_.angle_min = std::min(window_.angle_min, pinion);
  window_.angle_max = std::max(window_.angle_max, pinion);
  window_.torque_sum += torque;
  window_.speed_sum += speed;
  ++window_.n;
  if (window_.angle_max - window_.angle_min >= gear_turn_) result |= kSpans;
  return result;
}

void WindowAccumulator::interrupt() {
  window_.open = false;
  filtered_torque_.reset();
}

SteadyStretch WindowAccumulator::openStretch() const {
  SteadyStretch s;
  if (!window_.open || window_.n == 0) return s;
  const double n = static_cast<double>(window_.n);
  s.readings = window_.n;
  s.duration = window_.t1 - window_.t0;
  s.angle = window_.angle_max - window_.angle_min;
  s.torque = window_.torque_sum / n;
  s.speed = window_.speed_sum / n;
  return s;
}

bool WindowAccumulator::inBand(double torque) const {
  return std::abs(torque - window_.torque0) <=
         config_.torque_band + 0.01 * std::abs(window_.torque0);
}

double WindowAccumulator::meanTorque() const {
  const double n = static_cast<double>(window_.n);
  return window_.torque_sum / n;
}

double WindowAccumulator::meanSpeed() const {
  const double n = static_cast<double>(window_.n);
  return window_.speed_sum / n;
}

WindowOutcome WindowAccumulator::excitation(double speed, double duration, double lowest,
                                            double& value, double& limit) const {
  const double rpm = std::abs(speed) * 60.0 / kTwoPi;
  value = rpm;
  limit = config_.min_speed_rpm;
  if (rpm < config_.min_speed_rpm) return WindowOutcome::kTooSlow;
  const double mesh_hz = std::abs(speed) * pinion_teeth_ / kTwoPi;
  value = mesh_hz;
  limit = config_.max_mesh_to_natural * lowest;
  if (lowest > 0.0 && mesh_hz > config_.max_mesh_to_natural * lowest)
    return WindowOutcome::kNotQuasiStatic;
  // The second mesh harmonic below 0.45 of the reading rate (Nyquist with a margin).
  const double rate = duration > 0.0 ? static_cast<double>(window_.n - 1) / duration : 0.0;
  value = rate;
  limit = 2.0 * mesh_hz / 0.45;
  if (!(2.0 * mesh_hz < 0.45 * rate)) return WindowOutcome::kTooSparse;
  return WindowOutcome::kUpdated;
}

WindowOutcome WindowAccumulator::fit(double speed, double lowest, double& value, double& limit) {
  OrderRegression::Fit fit;
  WindowOutcome outcome = excitation(speed, window_.t1 - window_.t0, lowest, value, limit);
  if (outcome == WindowOutcome::kUpdated && !regression_.solve(fit)) {
    outcome = WindowOutcome::kIllConditioned;
    value = static_cast<double>(regression_.count());
    limit = 4.0 * regression_.terms();  // OrderRegression::solve's fewest readings
  }
  if (outcome != WindowOutcome::kUpdated) return outcome;
  last_fit_ = fit;
  has_fit_ = true;
  return outcome;
}

void WindowAccumulator::addBaseline(double torque, const StiffnessEstimator& supports,
                                    StaticTeModel& model) {
  // 3. The baseline: running means of the window fits (equal weights: the windows are alike).
  Baseline& b = baseline_;
  const OrderRegression::Fit& fit = last_fit_;
  const double k = static_cast<double>(++b.count);
  b.torque += (torque - b.torque) / k;
  b.mean += (fit.mean - b.mean) / k;
  for (int h = 0; h < OrderRegression::kMeshHarmonics; ++h)
    b.harmonics[h] += (fit.harmonics[h] - b.harmonics[h]) / k;
  // Variance of the running mean: the windows' own variances / k (between-window scatter is
  // checked by the NIS of the loaded windows).
  b.mean_var += (fit.mean_std * fit.mean_std - b.mean_var) / k;
  b.harm_var += (fit.harmonic_std * fit.harmonic_std - b.harm_var) / k;
  model.shaftDeflection(b.torque, supports, b.shafts);
}

void WindowAccumulator::features(double torque, const StiffnessEstimator& supports,
                                 StaticTeModel& model, FeatureVector& z, FeatureVector& z_std) {
  // 4. The features above the baseline, with their standard deviations: the fit's, the baseline's,
  // the model error and the floor, in quadrature.
  const OrderRegression::Fit& fit = last_fit_;
  const double kb = static_cast<double>(baseline_.count);
  z[0] = fit.mean - baseline_.mean;
  z_std[0] = std::sqrt(fit.mean_std * fit.mean_std + baseline_.mean_var / kb);
  for (int h = 0; h < kFeatureHarmonics; ++h) {
    z[1 + h] = std::abs(fit.harmonics[h] - baseline_.harmonics[h]);
    z_std[1 + h] = std::sqrt(fit.harmonic_std * fit.harmonic_std + baseline_.harm_var / kb);
  }
  model.shaftDeflection(torque, supports, shafts_);
  model.prepare(histogram_, regression_.count(), sampled_);
}

FeatureVector WindowAccumulator::predictFeatures(const StaticTeModel& model,
                                                 const CalibrationVector& p, double torque) const {
  return model.sampledFeatures(p, torque, shafts_, baseline_.torque, baseline_.shafts, sampled_);
}

std::uint32_t WindowAccumulator::countAtOperatingPoint(double torque) {
  const long key = std::lround(torque / (2.0 * config_.torque_band));
  int i = 0;
  while (i < bins_used_ && bin_key_[i] != key) ++i;
  if (i == bins_used_) {
    if (bins_used_ < kBins) {
      bin_key_[bins_used_++] = key;
    } else {
      i = kBins - 1;
    }
  }
  return ++bin_count_[i];
}

bool WindowAccumulator::sample(double te, double pinion, double phase, double torque,
                               const CalibrationVector& p, const StiffnessEstimator& supports,
                               StaticTeModel& model, MeasuredTeSample& sample) const {
  // 3. The processed reading, once a baseline and a fit exist.
  if (!(baseline_.count > 0 && has_fit_)) return false;
  double base = baseline_.mean;
  for (int k = 0; k < OrderRegression::kMeshHarmonics; ++k) {
    base += std::real(baseline_.harmonics[k] * std::polar(1.0, kTwoPi * (k + 1) * phase));
  }
  sample.te = te - base - regression_.orders(last_fit_, pinion);
  // The shafts' deflection: within the window's band, the one at the window's torque scaled to
  // this reading's (the bearings are smooth over a band); outside it (a step the filter has not
  // followed yet), the reading's own exact solution.
  std::array<double, 2> shafts{};
  if (inBand(torque) && window_.torque0 != 0.0) {
    const double scale = torque / window_.torque0;
    shafts = {window_.shafts[0] * scale, window_.shafts[1] * scale};
  } else {
    model.shaftDeflection(torque, supports, shafts);
  }
  sample.predicted = model.at(p, phase, torque, shafts, baseline_.torque, baseline_.shafts);
  sample.residual = sample.te - sample.predicted;
  sample.torque = torque;
  sample.phase = phase;
  return true;
}

}  // namespace drivetrain_stiffness

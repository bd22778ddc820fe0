#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/enum_names.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

namespace {
constexpr EnumName<SweepDirection> kSweepDirections[] = {
    {SweepDirection::kUp, "up"}, {SweepDirection::kDown, "down"}, {SweepDirection::kBoth, "both"}};
}  // namespace

const char* toString(SweepDirection d) { return enumName(kSweepDirections, d); }
SweepDirection parseSweepDirection(const std::string& field, const std::string& text) {
  return parseEnum(kSweepDirections, field, text);
}

std::vector<double> frequencyGrid(const std::string& field, double start, double stop,
                                  double step) {
  requireFinite(field + ".start", start);
  requirePositive(field + ".step", step);
  if (!(stop >= start)) throwInvalid(field + ".stop", stop, "must be >= " + field + ".start");
  const long n = static_cast<long>(std::floor((stop - start) / step + 1e-9));
  std::vector<double> grid;
  grid.reserve(n + 1);
  for (long i = 0; i <= n; ++i) grid.push_back(start + i * step);
  return grid;
}

double largestRelativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size())
    throwInvalid("responses", b.size(),
                 "points against " + std::to_string(a.size()) + ": must be equal");
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] >= 0.0 && b[i] >= 0.0))
      throwInvalid("response[" + std::to_string(i) + "]", std::min(a[i], b[i]), "must be >= 0");
    if (std::max(a[i], b[i]) > 0.0)
      worst = std::max(worst, std::abs(a[i] - b[i]) / std::max(a[i], b[i]));
  }
  return worst;
}

namespace {

void validateSweep(const RigConfig& rig, const SweepSpec& spec) {
  if (!rig.dynamics.present) throw InvalidInput("sweep: the gearbox file has no 'dynamics:' block");
  requirePositive("sweep.start", spec.start);
  requirePositive("sweep.step", spec.step);
  if (!(spec.stop >= spec.start)) throwInvalid("sweep.stop", spec.stop, "must be >= sweep.start");
  requirePositive("sweep.settle", spec.settle);
  requirePositive("sweep.measure", spec.measure);
  requireFinite("sweep.torque_amplitude", spec.torque_amplitude);
}

/// The number of excitation periods to measure at f [Hz]: at least `measure` [s] and three
/// periods, so the RMS of the forced part does not depend on where the window starts; the
/// mesh-frequency TE part is averaged over at least measure * f_mesh periods (17 at 1000 rpm with
/// the 50 ms default). Among up to twice that many periods, the count whose window is closest to a
/// whole number of mesh periods [s], so the TE part averages out as well.
double measuredPeriods(double f, double measure, double mesh_period) {
  const double p0 = std::max(3.0, std::ceil(measure * f - 1e-9));
  double periods = p0, best = 1.0;
  for (double q = p0; q <= 2.0 * p0; q += 1.0) {
    const double mesh_cycles = q / f / mesh_period;
    const double miss = std::abs(mesh_cycles - std::round(mesh_cycles)) / mesh_cycles;
    if (miss < best) {
      best = miss;
      periods = q;
    }
  }
  return periods;
}

/// The sweep's state across steps and directions: the time, the dynamics' state and the record
/// (one signal for the spectrum).
class SweepRun {
 public:
  SweepRun(const RigConfig& rig, const SweepSpec& spec) : spec_(spec) {
    const DynamicsConfig& d = rig.dynamics;
    mesh_ = std::make_shared<AntiBacklashMesh>(rig);
    StiffnessEstimator estimator(rig);
    estimator.setTorque(d.torque);
    const std::array<double, 2> kb = estimator.shaftRadialStiffness();
    p_ = rigRotorParameters(rig, *mesh_, kb);
    // One output step for the whole sweep: at least 20 samples per period of the highest
    // excitation, and a divisor of the mesh period.
    ex_.speed = d.speed_rpm * kTwoPi / 60.0;
    ex_.te_amplitude = spec.include_te ? d.transmission_error_amplitude : 0.0;
    ex_.backlash = d.backlash;
    ex_.torque.kind = TorqueProfile::Kind::kSine;
    ex_.torque.mean = d.torque;
    ex_.torque.amplitude = spec.torque_amplitude;
    mesh_period_ = 1.0 / RigExcitation(mesh_, p_, ex_).meshFrequency();
    dt_ = mesh_period_ / std::max(32.0, std::ceil(20.0 * spec.stop * mesh_period_));
  }

  double dt() const { return dt_; }
  bool recordTruncated() const { return record_truncated_; }
  const std::array<std::vector<double>, 3>& record() const { return record_; }

  /// Runs the steps in `order` [Hz]; returns the RMS [m] per coordinate in that order.
  std::array<std::vector<double>, 3> run(const std::vector<double>& order, bool keep_record) {
    std::array<std::vector<double>, 3> rms;
    for (double f : order) step(f, keep_record, rms);
    return rms;
  }

 private:
  /// One step at f [Hz]: settle, then measure; appends each coordinate's RMS to `rms`.
  void step(double f, bool keep_record, std::array<std::vector<double>, 3>& rms) {
    // Continuous torque at the step: 2 pi f_new t + phi_new = 2 pi f_old t + phi_old (mod 2 pi),
    // so the step itself does not kick the system onto another branch.
    if (started_)
      ex_.torque.retune(f, t_);
    else
      ex_.torque.frequency = f;
    const auto excitation = std::make_shared<RigExcitation>(mesh_, p_, ex_);
    const GearRotorModel model(p_, excitation);
    if (!started_) {
      y_ = staticEquilibrium(model, 0.0);
      started_ = true;
    }
    const double periods = measuredPeriods(f, spec_.measure, mesh_period_);
    const double dt = dt_;
    const long measured = std::max(1L, static_cast<long>(std::lround(periods / f / dt)));
    const long settled = static_cast<long>(std::ceil(spec_.settle / dt));
    const double t = t_;
    const double t_end = t + (settled + measured) * dt;
    const double t_measure = t_end - measured * dt + 0.5 * dt;
    std::array<double, 3> sum{}, sum2{};
    long count = 0;
    const Observer observe = [&](double ti, const State6& yi) {
      if (keep_record && ti > t) keep(yi);
      if (ti < t_measure) return;
      for (int c = 0; c < 3; ++c) {
        sum[c] += yi[c];
        sum2[c] += yi[c] * yi[c];
      }
      ++count;
    };
    if (spec_.fidelity == Fidelity::kFull) {
      IntegratorOptions o;
      o.relative_tolerance = 1e-8;
      o.absolute_tolerance = 1e-15;
      o.max_step = dt;
      y_ = integrate(model, IntegratorMethod::kDopri5, o, t, y_, t_end, dt, observe);
    } else {
      y_ = integrateReduced(model, spec_.fidelity, t, y_, t_end, dt, observe);
    }
    t_ = t_end;
    for (int c = 0; c < 3; ++c) {
      const double mean = sum[c] / count;
      rms[c].push_back(std::sqrt(std::max(sum2[c] / count - mean * mean, 0.0)));
    }
  }

  /// Appends a sample to the record, up to 4 Mi samples (96 MiB for three coordinates: a sweep
  /// through the kHz mesh mode would otherwise hold hundreds of MB); beyond, marks it truncated.
  void keep(const State6& yi) {
    constexpr std::size_t kMaxRecord = std::size_t{1} << 22;
    if (record_[0].size() < kMaxRecord) {
      for (int c = 0; c < 3; ++c) record_[c].push_back(yi[c]);
    } else {
      record_truncated_ = true;
    }
  }

  const SweepSpec& spec_;
  std::shared_ptr<AntiBacklashMesh> mesh_;
  GearRotorParameters p_;
  RigExcitationSpec ex_;
  double mesh_period_ = 0.0;
  double dt_ = 0.0;
  double t_ = 0.0;
  State6 y_;
  bool started_ = false;
  std::array<std::vector<double>, 3> record_;
  bool record_truncated_ = false;
};

/// The peaks of the RMS curve y over `frequency` [Hz] (grid step [Hz]) with at least 2 %
/// prominence: a "peak" that rises less than 2 % above the higher of the two minima separating it
/// from higher ground (or the curve's end) on either side is window ripple, not a resonance (on the
/// seed rig the x RMS is flat within 0.43 % over 60-3000 Hz).
std::vector<SpectralPeak> prominentPeaks(const std::vector<double>& frequency,
                                         const std::vector<double>& y, double step) {
  std::vector<SpectralPeak> peaks;
  for (const SpectralPeak& pk : curvePeaks(frequency, y, 3)) {
    const auto i = static_cast<long>(std::lround((pk.frequency - frequency.front()) / step));
    const long top = std::clamp(i, 0L, static_cast<long>(y.size()) - 1);
    double left = y[top], right = y[top];
    for (long j = top - 1; j >= 0 && y[j] <= y[top]; --j) left = std::min(left, y[j]);
    for (long j = top + 1; j < static_cast<long>(y.size()) && y[j] <= y[top]; ++j)
      right = std::min(right, y[j]);
    if (pk.amplitude > 1.02 * std::max(left, right)) peaks.push_back(pk);
  }
  return peaks;
}

}  // namespace

SweepOutput torqueSweep(const RigConfig& rig, const SweepSpec& spec) {
  validateSweep(rig, spec);
  SweepRun sweep(rig, spec);
  const double dt = sweep.dt();
  const std::vector<double> frequencies = frequencyGrid("sweep", spec.start, spec.stop, spec.step);

  SweepOutput out;
  out.frequency = frequencies;
  out.sample_interval = dt;
  std::vector<double> down(frequencies.rbegin(), frequencies.rend());
  if (spec.direction == SweepDirection::kDown) {
    out.rms = sweep.run(down, true);
    for (auto& r : out.rms) std::reverse(r.begin(), r.end());
  } else {
    out.rms = sweep.run(frequencies, true);
    if (spec.direction == SweepDirection::kBoth) {
      out.rms_down = sweep.run(down, false);
      for (auto& r : out.rms_down) std::reverse(r.begin(), r.end());
    }
  }
  if (out.frequency.size() >= 3) {
    for (int c = 0; c < 3; ++c) out.peaks[c] = prominentPeaks(out.frequency, out.rms[c], spec.step);
  }
  const std::array<std::vector<double>, 3>& record = sweep.record();
  if (!sweep.recordTruncated() && record[0].size() >= 8) {
    for (int c = 0; c < 3; ++c) {
      const Spectrum s = amplitudeSpectrum(record[c], dt);
      out.spectrum_peaks[c] = topPeaks(s, 3);
      out.spectrum_resolution = s.resolution;
    }
  }
  return out;
}

}  // namespace drivetrain_stiffness

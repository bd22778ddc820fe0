// Cost of the live calibration (docs/calibration.md, "Cost"): per encoder reading (the angle-domain
// regression's update) and per closed window (fit, features, iterated EKF, bands). Readings as the
// rig sim's load_sweep makes them: 120 rpm, 5 kHz, one gear turn (5,000 readings) per window.
//   devel/lib/drivetrain_stiffness/calibration_benchmark
#include <cmath>

#include <benchmark/benchmark.h>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

namespace {
using namespace drivetrain_stiffness;

RigConfig rig() {
  RigConfig r = loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  r.calibration.present = true;
  return r;
}

/// Readings of the nominal rig itself (its static encoder TE at each phase, plus a 1 um
/// manufacturing TE), so every loaded window passes the gate and runs the full update.
struct Feed {
  explicit Feed(const RigConfig& r, const StiffnessEstimator& s) : model(r) {
    p << 1.0, 1.0, 1.0, r.anti_backlash.preload_torque, 0.0;
    model.shaftDeflection(0.0, s, zero);
    model.shaftDeflection(2.0, s, loaded);
  }
  StaticTeModel model;
  CalibrationVector p;
  std::array<double, 2> zero{}, loaded{};
  double speed = 120.0 * kTwoPi / 60.0, rate = 5000.0;
  long i = 0;
  MeasuredTeSample sample;
  int next(Calibrator& c, const StiffnessEstimator& s, double torque) {
    const double t = i / rate, theta = speed * t;
    const double turns = 20.0 * theta / kTwoPi, phase = turns - std::floor(turns);
    const double x = (torque == 0.0 ? 0.0 : model.at(p, phase, torque, loaded, 0.0, zero)) + 1e-6 * std::sin(kTwoPi * phase);
    const double rbp = model.baseRadius()[0], rbg = model.baseRadius()[1];
    ++i;
    return c.reading(t, theta, (x - rbp * theta) / rbg, phase, speed, torque, s, sample);
  }
};

void BM_CalibratorReading(benchmark::State& state) {
  const RigConfig r = rig();
  StiffnessEstimator supports(r);
  Calibrator c(r);
  Feed feed(r, supports);
  for (int k = 0; k < 30000; ++k) feed.next(c, supports, 0.0);  // the baseline
  for (auto _ : state) benchmark::DoNotOptimize(feed.next(c, supports, 2.0));
  state.counters["updates"] = static_cast<double>(c.estimate().updates);
  state.counters["gated"] = static_cast<double>(c.estimate().gated);
}
BENCHMARK(BM_CalibratorReading);

void BM_CalibratorWindow(benchmark::State& state) {
  const RigConfig r = rig();
  StiffnessEstimator supports(r);
  Calibrator c(r);
  Feed feed(r, supports);
  for (int k = 0; k < 30000; ++k) feed.next(c, supports, 0.0);
  for (auto _ : state) {
    int out = 0;
    while (!(out & Calibrator::kWindow)) out = feed.next(c, supports, 2.0);  // one gear turn of readings, then the update
  }
  state.counters["updates"] = static_cast<double>(c.estimate().updates);
  state.counters["gated"] = static_cast<double>(c.estimate().gated);
}
BENCHMARK(BM_CalibratorWindow)->Unit(benchmark::kMillisecond);

/// The reading that closes a loaded window alone: fit, features, the iterated EKF and the bands.
void BM_CalibratorUpdate(benchmark::State& state) {
  const RigConfig r = rig();
  StiffnessEstimator supports(r);
  Calibrator c(r);
  Feed feed(r, supports);
  for (int k = 0; k < 30000; ++k) feed.next(c, supports, 0.0);
  while (!(feed.next(c, supports, 2.0) & Calibrator::kWindow)) {}
  for (auto _ : state) {
    state.PauseTiming();
    for (int k = 0; k < 4990; ++k) feed.next(c, supports, 2.0);  // a gear turn is 5,000 readings here
    state.ResumeTiming();
    while (!(feed.next(c, supports, 2.0) & Calibrator::kWindow)) {}
  }
  state.counters["updates"] = static_cast<double>(c.estimate().updates);
}
BENCHMARK(BM_CalibratorUpdate)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

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
#include "static_te_encoder.hpp"  // NOLINT(build/include_subdir)

namespace {
using namespace drivetrain_stiffness;

RigConfig rig() {
  RigConfig r =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  r.calibration.present = true;
  return r;
}

/// Readings of the nominal rig itself (its static encoder TE at each phase, plus a 1 um
/// manufacturing TE), so every loaded window passes the gate and runs the full update.
struct Feed {
  explicit Feed(const RigConfig& r) : encoder(r, 2.0, 1e-6) {}
  test::StaticTeEncoder encoder;
  double speed = 120.0 * kTwoPi / 60.0, rate = 5000.0;
  long i = 0;
  MeasuredTeSample sample;
  int next(Calibrator& c, const StiffnessEstimator& s, double torque) {
    const double t = i / rate, theta = speed * t;
    ++i;
    return c.reading(t, theta, encoder.gearAngle(theta, torque), encoder.phase(theta), speed,
                     torque, s, sample);
  }
};

/// A calibrator past its baseline (30,000 readings at 0 N*m), fed the nominal rig at 2 N*m.
struct Warmed {
  Warmed() : r(rig()), supports(r), c(r), feed(r) {
    for (int k = 0; k < 30000; ++k) feed.next(c, supports, 0.0);
  }
  int next() { return feed.next(c, supports, 2.0); }
  void report(benchmark::State& state) const {
    state.counters["updates"] = static_cast<double>(c.estimate().updates);
    state.counters["gated"] = static_cast<double>(c.estimate().gated);
  }
  RigConfig r;
  StiffnessEstimator supports;
  Calibrator c;
  Feed feed;
};

void BM_CalibratorReading(benchmark::State& state) {
  Warmed w;
  for (auto _ : state) benchmark::DoNotOptimize(w.next());
  w.report(state);
}
BENCHMARK(BM_CalibratorReading);

void BM_CalibratorWindow(benchmark::State& state) {
  Warmed w;
  for (auto _ : state) {
    while (!(w.next() & Calibrator::kWindow)) {
    }  // one gear turn of readings, then the update
  }
  w.report(state);
}
BENCHMARK(BM_CalibratorWindow)->Unit(benchmark::kMillisecond);

/// The reading that closes a loaded window alone: fit, features, the iterated EKF and the bands.
void BM_CalibratorUpdate(benchmark::State& state) {
  Warmed w;
  while (!(w.next() & Calibrator::kWindow)) {
  }
  for (auto _ : state) {
    state.PauseTiming();
    for (int k = 0; k < 4990; ++k) w.next();  // a gear turn is 5,000 readings here
    state.ResumeTiming();
    while (!(w.next() & Calibrator::kWindow)) {
    }
  }
  w.report(state);
}
BENCHMARK(BM_CalibratorUpdate)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

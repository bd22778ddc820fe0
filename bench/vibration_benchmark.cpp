// Cost of the vibration path (docs/vibration.md "Cost in the pipeline"): one accelerometer block
// (2 channels x 1024 samples at 51.2 kHz) through RigPipeline::vibration, with the modal stage on
// (the block's angles noted; the identification off this path) and off; and one pipeline
// identification (identifyModes: orders out, SSI-COV with std at the pipeline's defaults, pole
// selection, matching) of a record of 1, 4 and 20 s, with its real-time factor.
//   devel/lib/drivetrain_stiffness/vibration_benchmark --benchmark_repetitions=3
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/pipeline/modal_identification.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "synthetic_modes.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

constexpr double kFs = 51200.0;

const RigConfig& rig() {
  static const RigConfig r = loadRigFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  return r;
}

void vibrationBlocks(benchmark::State& state, bool identify) {
  PipelineOptions o;
  o.modal_identification = identify;
  o.vibration_record = 600.0;  // no identification inside the timed loop
  RigPipeline pipeline(rig(), o);
  PipelineSink sink;
  const std::vector<std::string> channels{"pinion_bearing", "gear_bearing"};
  std::vector<float> data(2 * 1024);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<float>(std::sin(0.37 * i));
  const VibrationBlockView block{kFs, channels.data(), 2, data.data(), data.size()};
  const std::int64_t period_ns = std::llround(1024 / kFs * 1e9);
  Stamp stamp{1767225600LL * 1000000000LL};
  pipeline.torque(stamp, 0.5, sink);
  for (auto _ : state) {
    stamp.ns += period_ns;
    benchmark::DoNotOptimize(pipeline.vibration(stamp, block, sink));
  }
  state.counters["blocks_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
void BM_VibrationBlockModalOn(benchmark::State& s) { vibrationBlocks(s, true); }
void BM_VibrationBlockModalOff(benchmark::State& s) { vibrationBlocks(s, false); }
BENCHMARK(BM_VibrationBlockModalOn)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VibrationBlockModalOff)->Unit(benchmark::kMicrosecond);

/// A job as the stage builds it: the rig's two transverse modes on two channels, a mesh line,
/// the nominal angle at 1000 rpm, the seed rig's predicted modes.
ModalJob job(double seconds) {
  ModalJob j;
  const long n = std::lround(seconds * kFs);
  j.record = modal::test::rigModes(kFs).record(n, 7);
  j.angle.resize(n);
  const double speed = 1000.0 * kTwoPi / 60.0;  // [rad/s]
  for (long t = 0; t < n; ++t) {
    j.angle[t] = speed * t / kFs;
    j.record(0, t) += 0.5 * std::sin(28 * 20 * j.angle[t]);
  }
  j.sample_rate = kFs;
  j.end = Stamp{std::llround(seconds * 1e9)};
  j.channels = {"pinion_bearing", "gear_bearing"};
  j.channel_shaft = {0, 1};
  j.pinion_teeth = 20;
  j.gear_teeth = 40;
  const char* names[3] = {"x_g", "x_p", "x"};
  const double f[3] = {7884.0, 9377.0, 61258.0};
  for (int k = 0; k < 3; ++k) {
    j.predicted[k].dominant = names[k];
    j.predicted[k].frequency = j.predicted[k].low = j.predicted[k].high = f[k];
    j.predicted[k].shape = Eigen::Vector3d::Unit(k == 0 ? 1 : k == 1 ? 0 : 2);
  }
  return j;
}

void BM_IdentifyRecord(benchmark::State& state) {
  const double seconds = static_cast<double>(state.range(0));
  const ModalJob j = job(seconds);
  std::size_t modes = 0;
  for (auto _ : state) {
    const ModalReport r = identifyModes(j);
    modes = r.modes.size();
    benchmark::DoNotOptimize(modes);
  }
  state.counters["modes"] = static_cast<double>(modes);
  // Seconds of record identified per second of CPU: the real-time factor at one identification
  // per record.
  state.counters["realtime_factor"] = benchmark::Counter(
      seconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IdentifyRecord)->Arg(1)->Arg(4)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

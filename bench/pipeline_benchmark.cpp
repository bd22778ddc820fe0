// RigPipeline per torque input at 10 kHz, full dynamics, with a sink that only reads the outputs:
// an input processed in full (stiffness update, bearing handover, resonance check, stiffness
// output) against one shed under backlog (rules and dynamics only), the ratio that tells how much
// an overloaded node gains by shedding (docs/reliability.md, "Overload"). The node adds roscpp's
// deserialization and one publish per output on top.
// Run: build/devel/lib/drivetrain_stiffness/pipeline_benchmark --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

using namespace drivetrain_stiffness;

namespace {

struct ReadingSink : PipelineSink {
  double sum = 0.0;
  void stiffness(Stamp, const StiffnessEstimate& e) override { sum += e.mesh.current.composite; }
  void transmissionError(Stamp, const DynamicsSample& s) override { sum += s.dynamic_te; }
};

void torqueInputs(benchmark::State& state, Backlog backlog) {
  const RigConfig rig = loadRigFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  RigPipeline pipeline(rig, PipelineOptions{});
  ReadingSink sink;
  constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;
  std::int64_t k = 0;
  const auto input = [&](Backlog b) {
    const double t = 1e-4 * static_cast<double>(k);  // 10 kHz
    const double torque = 0.1 * (1.0 + 0.1 * std::sin(2.0 * M_PI * 100.0 * t));  // the soak's 100 Hz ripple
    pipeline.torque(Stamp{kEpoch + 100000 * k}, torque, sink, {"/rig", static_cast<std::uint32_t>(k), "pinion"}, b);
    ++k;
  };
  for (int i = 0; i < 10000; ++i) input(Backlog::kNone);  // 1 s of warm-up: tables, propagators, spectra
  for (auto _ : state) input(backlog);
  benchmark::DoNotOptimize(sink.sum);
  state.counters["model_s_per_s"] = benchmark::Counter(1e-4 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

static void BM_TorqueInputFull(benchmark::State& state) { torqueInputs(state, Backlog::kNone); }
BENCHMARK(BM_TorqueInputFull);

static void BM_TorqueInputShed(benchmark::State& state) { torqueInputs(state, Backlog::kShed); }
BENCHMARK(BM_TorqueInputShed);

BENCHMARK_MAIN();

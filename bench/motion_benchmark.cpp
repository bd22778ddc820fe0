// Following the rig's measured motion (docs/model.md, "Following the rig's motion"):
//  - BM_SlicedPropagation/<rpm>: SlicedModalPropagator over 1 ms steps at a constant speed, the
//    cost per simulated second and per slice crossed (the work grows with speed x slices);
//  - BM_SliceDecomposition: every slice decomposed again and crossed once (what a bearing-stiffness
//    change costs, spread over the slices as they are crossed);
//  - BM_AdvanceAfterBearingChange/<rpm>: the 1 ms advance right after a 1 % bearing change to a
//    value never met before, which at 2000 rpm and more crosses (and so decomposes) every slice in
//    one callback; BM_AdvanceAfterKeptBearingChange/<rpm>: the same back to a value whose slices
//    are kept (none decomposed);
//  - BM_PipelineEncoderRunUp: RigPipeline with torque and joint_states at 1 kHz each through a
//    run-up 0 -> 6000 rpm in 10 s (model seconds per second of work = the real-time factor).
// Run: devel/lib/drivetrain_stiffness/motion_benchmark --benchmark_repetitions=3
// --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() {
  static const RigConfig r = loadRigFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  return r;
}
std::shared_ptr<const AntiBacklashMesh> mesh() {
  static const auto m = std::make_shared<const AntiBacklashMesh>(
      rig().gears, rig().anti_backlash, rig().mesh_model, rig().mesh_samples);
  return m;
}

}  // namespace

static void BM_SlicedPropagation(benchmark::State& state) {
  const double rpm = static_cast<double>(state.range(0));
  const GearRotorParameters p = rigRotorParameters(rig(), *mesh(), {1.2e8, 1.2e8});
  SlicedModalPropagator prop(p, std::make_shared<const SlicedMesh>(mesh(), 256), 1e-6, 0.0);
  const double f = rpm / 60.0 * 20.0, force = 0.1 / p.pinion_base_radius;
  State6 y = State6::Zero();
  y[2] = force / 2e8;
  double phase = 0.0;
  for (int i = 0; i < 100; ++i) prop.propagate(y, phase, f, 1e-3, force);  // every slice decomposed
  const long crossed0 = prop.slicesCrossed();
  for (auto _ : state) {
    if (!prop.propagate(y, phase, f, 1e-3, force)) state.SkipWithError("left the linear regime");
  }
  benchmark::DoNotOptimize(y);
  state.counters["model_s_per_s"] = benchmark::Counter(
      1e-3 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["crossings_per_step"] =
      static_cast<double>(prop.slicesCrossed() - crossed0) /
      static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
}
BENCHMARK(BM_SlicedPropagation)->Arg(100)->Arg(1000)->Arg(6000);

static void BM_SliceDecomposition(benchmark::State& state) {
  GearRotorParameters p = rigRotorParameters(rig(), *mesh(), {1.2e8, 1.2e8});
  auto slices = std::make_shared<const SlicedMesh>(mesh(), 256);
  SlicedModalPropagator prop(p, slices, 1e-6, 0.0);
  State6 y = State6::Zero();
  y[2] = 17.7 / 2e8;
  double phase = 0.0;
  long k = 0;
  for (auto _ : state) {
    // A value not met before (a kept set would come back with no work): every slice decomposed
    // again on its next use.
    p.bearing_stiffness[0] = 1.2e8 * (1.0 + 1e-9 * static_cast<double>(++k));
    prop.setParameters(p);
    // One mesh period at 1000 rpm crosses every slice once: one decomposition each.
    prop.propagate(y, phase, 333.33333333333331, 3e-3, 17.7);
  }
  state.counters["decompositions_per_iteration"] =
      static_cast<double>(prop.decompositions()) /
      static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
}
BENCHMARK(BM_SliceDecomposition)->Unit(benchmark::kMicrosecond);

// The callback right after a bearing-stiffness change at 6000 rpm: one 1 ms advance crosses every
// slice twice, so it makes all 259 decompositions itself (the aim: under 0.5 ms). The bearing
// stiffness alternates by 1 % (a preload step) and drifts by a further 1e-9 at each change (k 1e-9
// after k changes), so every value is new (none of the kept parameter sets) and each slice is
// seeded by the neighbour behind it under the new parameters, as in the pipeline; compare with
// BM_SlicedPropagation/6000, the same
// advance without a change. BM_AdvanceAfterKeptBearingChange: the same two values exactly, as a
// rippling load's stiffness comes back to its grid values: their slices are kept.
static void advanceAfterBearingChange(benchmark::State& state, double drift) {
  const double rpm = static_cast<double>(state.range(0));
  GearRotorParameters p[2] = {rigRotorParameters(rig(), *mesh(), {1.2e8, 1.2e8}),
                              rigRotorParameters(rig(), *mesh(), {1.212e8, 1.212e8})};
  SlicedModalPropagator prop(p[0], std::make_shared<const SlicedMesh>(mesh(), 256), 1e-6, 0.0);
  const double f = rpm / 60.0 * 20.0, force = 0.1 / p[0].pinion_base_radius;
  State6 y = State6::Zero();
  y[2] = force / 2e8;
  double phase = 0.0;
  for (int i = 0; i < 10; ++i) prop.propagate(y, phase, f, 1e-3, force);
  long k = 0;
  const long general0 = prop.generalDecompositions(), all0 = prop.decompositions();
  for (auto _ : state) {
    GearRotorParameters next = p[++k % 2];
    next.bearing_stiffness[0] *= 1.0 + drift * static_cast<double>(k);
    prop.setParameters(next);
    if (!prop.propagate(y, phase, f, 1e-3, force)) state.SkipWithError("left the linear regime");
  }
  benchmark::DoNotOptimize(y);
  const double n = static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
  state.counters["decompositions_per_advance"] =
      static_cast<double>(prop.decompositions() - all0) / n;
  state.counters["general_per_advance"] =
      static_cast<double>(prop.generalDecompositions() - general0) / n;
}
static void BM_AdvanceAfterBearingChange(benchmark::State& state) {
  advanceAfterBearingChange(state, 1e-9);
}
BENCHMARK(BM_AdvanceAfterBearingChange)->Arg(2000)->Arg(6000)->Unit(benchmark::kMicrosecond);
static void BM_AdvanceAfterKeptBearingChange(benchmark::State& state) {
  advanceAfterBearingChange(state, 0.0);
}
BENCHMARK(BM_AdvanceAfterKeptBearingChange)->Arg(6000)->Unit(benchmark::kMicrosecond);

static void BM_PipelineEncoderRunUp(benchmark::State& state) {
  RigPipeline pipeline(rig(), PipelineOptions{});
  PipelineSink sink;
  constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;
  const double a = 6000.0 / 60.0 * kTwoPi / 10.0;  // [rad/s^2]: 0 -> 6000 rpm in 10 s
  long k = 0;
  auto step = [&] {
    const double t =
        1e-3 * static_cast<double>(k % 10000);  // the run-up repeats (a restart every 10 s)
    const std::int64_t ns = kEpoch + 1000000LL * k;
    pipeline.torque(Stamp{ns}, 0.1, sink);
    MotionInput m;
    m.pinion_angle = std::remainder(0.5 * a * t * t, kTwoPi);
    m.pinion_velocity = a * t;
    pipeline.motion(Stamp{ns + 500000}, m, sink);
    ++k;
  };
  for (int i = 0; i < 1000; ++i) step();
  for (auto _ : state) step();
  state.counters["model_s_per_s"] = benchmark::Counter(
      1e-3 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["dynamics_errors"] = static_cast<double>(pipeline.counters().dynamics_errors);
}
BENCHMARK(BM_PipelineEncoderRunUp)->Iterations(10000);

BENCHMARK_MAIN();

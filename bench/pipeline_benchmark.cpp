// RigPipeline per torque input at 10 kHz, full dynamics, with a sink that only reads the outputs:
// an input processed in full (stiffness update, bearing handover, resonance check, stiffness
// output) against one shed under backlog (rules and dynamics only), the ratio that tells how much
// an overloaded node gains by shedding (docs/reliability.md, "Overload"). The node adds roscpp's
// deserialization and one publish per output on top. BM_TorqueStepResponse: what a torque input
// stamped between two output samples adds at the nominal phase (the own-stamp rule: the exact
// response to a unit step at its instant, PeriodicExponentialPropagator::torqueStepResponse), at
// the live 1 kHz output grid of the seed rig at 1000 rpm. BM_ExponentialSetUp: building those
// propagators. Run: devel/lib/drivetrain_stiffness/pipeline_benchmark --benchmark_repetitions=3
// --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "ripple_torque_feed.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

void torqueInputs(benchmark::State& state, Backlog backlog) {
  const RigConfig rig = loadRigFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  RigPipeline pipeline(rig, PipelineOptions{});
  RippleTorqueFeed feed(pipeline);
  for (int i = 0; i < 10000; ++i) feed.next();  // 1 s of warm-up: tables, propagators, spectra
  for (auto _ : state) feed.next(backlog);
  benchmark::DoNotOptimize(feed.checksum());
  state.counters["model_s_per_s"] =
      benchmark::Counter(RippleTorqueFeed::kInterval * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
}

}  // namespace

static void BM_TorqueInputFull(benchmark::State& state) { torqueInputs(state, Backlog::kNone); }
BENCHMARK(BM_TorqueInputFull);

static void BM_TorqueInputShed(benchmark::State& state) { torqueInputs(state, Backlog::kShed); }
BENCHMARK(BM_TorqueInputShed);

static void BM_TorqueStepResponse(benchmark::State& state) {
  const RigConfig rig = loadRigFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  DynamicsEstimator dynamics(rig, {1.2e8, 1.2e8}, 1000.0);
  dynamics.reset(0.0, 0.1);
  const PeriodicExponentialPropagator propagator(dynamics.rotorModel(), 0.0,
                                                 dynamics.outputInterval());
  long k = 0;
  for (auto _ : state) {
    // Instants spread over the interval (golden-ratio steps), intervals over the mesh period.
    const double offset =
        dynamics.outputInterval() *
        (0.6180339887 * static_cast<double>(k) - std::floor(0.6180339887 * static_cast<double>(k)));
    benchmark::DoNotOptimize(propagator.torqueStepResponse(k++, offset));
  }
}
BENCHMARK(BM_TorqueStepResponse);

// The node's set-up of the exponential propagators at the nominal phase (at start-up and after a
// rebuild): one mesh period of 4th-order Magnus steps (an 11x11 block-triangular exponential
// each), the node products for torque steps and the settling table, seed rig at 1000 rpm, 1 kHz.
static void BM_ExponentialSetUp(benchmark::State& state) {
  const RigConfig rig = loadRigFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  DynamicsEstimator dynamics(rig, {1.2e8, 1.2e8}, 1000.0);
  dynamics.reset(0.0, 0.1);
  long steps = 0;
  for (auto _ : state) {
    const PeriodicExponentialPropagator propagator(dynamics.rotorModel(), 0.0,
                                                   dynamics.outputInterval(), 1.0, true);
    steps = propagator.magnusSteps();
    benchmark::DoNotOptimize(propagator.monodromy());
  }
  state.counters["magnus_steps"] = static_cast<double>(steps);
}
BENCHMARK(BM_ExponentialSetUp)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();

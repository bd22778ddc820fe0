// One bearing-stiffness update for the 7013 AC (19 balls, seed 003 Table 1): warm-started (the
// node's steady state: a new radial load, solved from the previous displacement) and cold (no
// previous solution), plus a rebuild of the bearing after a preload or fit change.
// Run: devel/lib/drivetrain_stiffness/bearing_benchmark (figures: docs/performance.md).
#include <benchmark/benchmark.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"

using namespace drivetrain_stiffness;

namespace {
const BearingSupportConfig& config() {
  static const BearingSupportConfig c =
      loadBearingFile(DRIVETRAIN_SOURCE_DIR "/config/bearings/7013ac.yaml");
  return c;
}
BearingSupport support() {
  return BearingSupport(config().spec, config().arrangement, 1000.0, config().interference,
                        config().tilt);
}
}  // namespace

static void BM_WarmUpdate7013(benchmark::State& state) {
  const BearingSupport s = support();
  Vector5d load = Vector5d::Zero();
  load[kUx] = 500.0;
  BearingSolution sol = s.solve(load);
  double fr = 500.0;
  for (auto _ : state) {
    fr = fr > 600.0 ? 500.0 : fr + 1.0;  // a slowly varying mesh load, as from a torque stream
    load[kUx] = fr;
    sol = s.solve(load, &sol.displacement);
    benchmark::DoNotOptimize(sol.stiffness(0, 0));
  }
}
BENCHMARK(BM_WarmUpdate7013);

static void BM_ColdUpdate7013(benchmark::State& state) {
  const BearingSupport s = support();
  Vector5d load = Vector5d::Zero();
  load[kUx] = 500.0;
  for (auto _ : state) {
    BearingSolution sol = s.solve(load);
    benchmark::DoNotOptimize(sol.stiffness(0, 0));
  }
}
BENCHMARK(BM_ColdUpdate7013);

static void BM_RebuildAndColdUpdate7013(benchmark::State& state) {
  Vector5d load = Vector5d::Zero();
  load[kUx] = 500.0;
  double inner = 2e-6;
  for (auto _ : state) {
    inner =
        inner > 8e-6 ? 2e-6 : inner + 1e-7;  // a new interference: new geometry and Hertz constants
    const BearingSupport s(config().spec, config().arrangement, 1000.0, Interference{inner, 0.0},
                           config().tilt);
    BearingSolution sol = s.solve(load);
    benchmark::DoNotOptimize(sol.stiffness(0, 0));
  }
}
BENCHMARK(BM_RebuildAndColdUpdate7013);

BENCHMARK_MAIN();

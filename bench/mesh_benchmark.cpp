// Mesh stiffness: table lookup by mesh phase (the hot path of the dynamics) and table rebuild (when
// a gear parameter changes), for the seed-000 anti-backlash pair with the potential-energy model.
// Run: build/devel/lib/drivetrain_stiffness/mesh_benchmark (see README for the figures).
#include <benchmark/benchmark.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"

using namespace drivetrain_stiffness;

namespace {
const RigConfig& rig() {
  static const RigConfig r = loadGearFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  return r;
}
}  // namespace

static void BM_CompositeLookup(benchmark::State& state) {
  const AntiBacklashMesh mesh(rig().gears, rig().anti_backlash, MeshStiffnessModel::kPotentialEnergy, 256);
  double phase = 0.0;
  for (auto _ : state) {
    phase += 0.0123456;  // sweep the period like a rotating pinion
    if (phase >= 1.0) phase -= 1.0;
    benchmark::DoNotOptimize(mesh.at(phase, 17.7).composite);
  }
}
BENCHMARK(BM_CompositeLookup);

static void BM_DriveLookup(benchmark::State& state) {
  const AntiBacklashMesh mesh(rig().gears, rig().anti_backlash, MeshStiffnessModel::kPotentialEnergy, 256);
  double phase = 0.0;
  for (auto _ : state) {
    phase += 0.0123456;
    if (phase >= 1.0) phase -= 1.0;
    benchmark::DoNotOptimize(mesh.driveTable().drive(phase));
  }
}
BENCHMARK(BM_DriveLookup);

static void BM_RebuildTables(benchmark::State& state) {
  const auto model = static_cast<MeshStiffnessModel>(state.range(0));
  for (auto _ : state) {
    const AntiBacklashMesh mesh(rig().gears, rig().anti_backlash, model, 256);
    benchmark::DoNotOptimize(mesh.driveTable().pair(0.002));
  }
  state.SetLabel(toString(model));
}
BENCHMARK(BM_RebuildTables)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();

// Mesh stiffness: table lookup by mesh phase (the hot path of the dynamics) and table rebuild (when
// a gear parameter changes), for the seed-000 anti-backlash pair with the potential-energy model.
// Run: devel/lib/drivetrain_stiffness/mesh_benchmark (figures: docs/performance.md).
#include <benchmark/benchmark.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"

using namespace drivetrain_stiffness;

namespace {
const RigConfig& rig() {
  static const RigConfig r =
      loadGearFile(DRIVETRAIN_SOURCE_DIR "/config/gearboxes/seed_servo.yaml");
  return r;
}
}  // namespace

static void BM_CompositeLookup(benchmark::State& state) {
  const AntiBacklashMesh mesh(rig().gears, rig().anti_backlash,
                              MeshStiffnessModel::kPotentialEnergy, 256);
  double phase = 0.0;
  for (auto _ : state) {
    phase += 0.0123456;  // sweep the period like a rotating pinion
    if (phase >= 1.0) phase -= 1.0;
    benchmark::DoNotOptimize(mesh.at(phase, 17.7).composite);
  }
}
BENCHMARK(BM_CompositeLookup);

static void BM_DriveLookup(benchmark::State& state) {
  const AntiBacklashMesh mesh(rig().gears, rig().anti_backlash,
                              MeshStiffnessModel::kPotentialEnergy, 256);
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

// One modal update at the operating point (the aim: under 10 us): 3x3 generalised
// eigenproblem plus the 6x6 state-space eigenvalues.
static void BM_ModalUpdate(benchmark::State& state) {
  GearRotorParameters p;
  p.pinion_mass = 33.95e-3;
  p.gear_mass = 48.27e-3;
  p.pinion_inertia = 0.0515e-6;
  p.gear_inertia = 0.258e-6;
  p.pinion_base_radius = 5.638e-3;
  p.gear_base_radius = 11.276e-3;
  p.bearing_stiffness = {1.2e8, 1.2e8};
  p.bearing_damping = {80.0, 95.0};
  p.mesh_damping = 34.0;
  double ks = 1.2e8;
  for (auto _ : state) {
    ks = ks > 1.5e8 ? 0.9e8 : ks + 1e5;
    benchmark::DoNotOptimize(modalAnalysis(p, ks)[0].natural_frequency);
  }
}
BENCHMARK(BM_ModalUpdate);

BENCHMARK_MAIN();

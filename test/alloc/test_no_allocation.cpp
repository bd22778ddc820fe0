// The per-input hot path allocates nothing in steady state: a counting global operator new (this
// binary only) around torque inputs to a warmed-up RigPipeline with full dynamics (bearing solves,
// mesh lookup, dynamics, TE spectrum, resonance check), solved in full or shed. Preload inputs
// still allocate (a changed support is rebuilt): not covered here.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace drivetrain_stiffness;

namespace {

struct ReadingSink : PipelineSink {
  double sum = 0.0;
  void stiffness(Stamp, const StiffnessEstimate& e) override { sum += e.mesh.current.composite; }
  void transmissionError(Stamp, const DynamicsSample& s) override { sum += s.dynamic_te; }
};

constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;

// Torque inputs to a warmed-up pipeline (2 s of 10 kHz inputs: tables, propagators, a full
// spectrum window), then 1 s more counted: none may allocate.
long allocationsPerSecondOfInputs(const PipelineOptions& options, Backlog backlog) {
  const RigConfig rig = loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  RigPipeline pipeline(rig, options);
  ReadingSink sink;
  long k = 0;
  const auto input = [&](Backlog b) {
    const double t = 1e-4 * static_cast<double>(k);
    const double torque = 0.1 * (1.0 + 0.1 * std::sin(2.0 * M_PI * 100.0 * t));  // the soak's ripple
    pipeline.torque(Stamp{kEpoch + 100000 * k}, torque, sink, {"/rig", static_cast<std::uint32_t>(k), "pinion"}, b);
    ++k;
  };
  for (int i = 0; i < 20000; ++i) input(Backlog::kNone);
  const long before = g_allocations.load();
  for (int i = 0; i < 10000; ++i) input(backlog);
  return g_allocations.load() - before;
}

}  // namespace

TEST(NoAllocation, TorqueInputsResolvingEveryBearing) {
  PipelineOptions options;
  options.limits.load_tolerance = 0.0;  // every input re-solves every bearing: the worst case
  const long n = allocationsPerSecondOfInputs(options, Backlog::kNone);
  EXPECT_EQ(n, 0) << n / 1e4 << " heap allocations per torque input";
}

TEST(NoAllocation, TorqueInputsWithTheDefaultTolerance) {
  const long n = allocationsPerSecondOfInputs(PipelineOptions{}, Backlog::kNone);
  EXPECT_EQ(n, 0) << n / 1e4 << " heap allocations per torque input";
}

TEST(NoAllocation, ShedTorqueInputs) {
  const long n = allocationsPerSecondOfInputs(PipelineOptions{}, Backlog::kShed);
  EXPECT_EQ(n, 0) << n / 1e4 << " heap allocations per shed torque input";
}

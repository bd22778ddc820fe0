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
#include "ripple_torque_feed.hpp"  // NOLINT(build/include_subdir)
#include "seed_rig.hpp"            // NOLINT(build/include_subdir)
#include "static_te_encoder.hpp"   // NOLINT(build/include_subdir)

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

// Torque inputs to a warmed-up pipeline (2 s of 10 kHz inputs: tables, propagators, a full
// spectrum window), then 1 s more counted: none may allocate.
long allocationsPerSecondOfInputs(const PipelineOptions& options, Backlog backlog) {
  RigPipeline pipeline(test::seedServo(), options);
  RippleTorqueFeed feed(pipeline);
  for (int i = 0; i < 20000; ++i) feed.next();
  const long before = g_allocations.load();
  for (int i = 0; i < 10000; ++i) feed.next(backlog);
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

// Following the encoders: torque and joint_states at 1 kHz each through a run-up 300 -> 3000 rpm
// (the speed changes at every reading), warmed up for 1 s (every slice decomposed), then 1 s
// counted: the exact propagation at the measured speed allocates nothing either.
TEST(NoAllocation, TorqueAndEncoderInputsThroughARunUp) {
  RigPipeline pipeline(test::seedServo(), PipelineOptions{});
  PipelineSink sink;
  using test::kEpoch;
  const double w0 = 300.0 / 60.0 * 2.0 * M_PI, a = (3000.0 - 300.0) / 60.0 * 2.0 * M_PI / 2.0;
  auto step = [&](int k) {
    const double t = 1e-3 * k;
    pipeline.torque(Stamp{kEpoch + 1000000LL * k}, 0.1, sink);
    MotionInput m;
    m.pinion_angle = std::remainder(w0 * t + 0.5 * a * t * t, 2.0 * M_PI);
    m.pinion_velocity = w0 + a * t;
    pipeline.motion(Stamp{kEpoch + 1000000LL * k + 400000LL}, m, sink);
  };
  for (int k = 0; k < 1000; ++k) step(k);
  const long before = g_allocations.load();
  for (int k = 1000; k < 2000; ++k) step(k);
  const long n = g_allocations.load() - before;
  EXPECT_EQ(n, 0) << n / 2e3 << " heap allocations per input";
  EXPECT_EQ(pipeline.counters().accepted_motion, 2000u);
  EXPECT_STREQ(pipeline.phaseSource(), "encoders");
}

// The live calibration (rule 11) on the per-reading path: torque at 1 kHz and joint_states with
// both joints at 5 kHz, 120 rpm, the gear angle carrying the static model's TE (so loaded windows
// pass the gate and run the whole update: fit, iterated EKF, bands, modal analyses). Warmed up
// through a baseline and the first loaded windows, then 2 s (two gear turns, two updates) counted.
TEST(NoAllocation, EncoderReadingsThroughCalibrationUpdates) {
  RigConfig rig = test::seedServo();
  rig.calibration.present = true;
  RigPipeline pipeline(rig, PipelineOptions{});
  ASSERT_NE(pipeline.calibrator(), nullptr);
  PipelineSink sink;
  const test::StaticTeEncoder encoder(rig, 2.0);
  const double w = 120.0 / 60.0 * 2.0 * M_PI;
  auto step = [&](int k) {  // k: 5 kHz ticks
    const double t = 2e-4 * k, torque = t < 1.5 ? 0.0 : 2.0;
    if (k % 5 == 0) pipeline.torque(Stamp{test::kEpoch + 200000LL * k}, torque, sink);
    pipeline.motion(Stamp{test::kEpoch + 200000LL * k + 100000LL}, encoder.reading(w * t, w, torque), sink);
  };
  for (int k = 0; k < 25000; ++k) step(k);  // 5 s: baseline, then loaded windows
  const std::uint64_t updates_before = pipeline.calibrator()->estimate().updates;
  const long before = g_allocations.load();
  for (int k = 25000; k < 35000; ++k) step(k);
  const long n = g_allocations.load() - before;
  EXPECT_EQ(n, 0) << n / 1e4 << " heap allocations per reading";
  EXPECT_GE(pipeline.calibrator()->estimate().updates, updates_before + 2);
  EXPECT_EQ(pipeline.calibrator()->estimate().gated, 0u);
}

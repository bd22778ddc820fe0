// MeshPeriodStage on synthetic samples of known statistics: a block of whole mesh periods closes
// where the phase says, its means are the exact ones (the mesh force's from the momentum balance),
// a restart drops the running block, and a reversal counts periods backward.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drivetrain_stiffness/pipeline/mesh_period_stage.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

struct Blocks : PipelineSink {
  std::vector<MeshPeriodStatistics> out;
  void meshPeriod(Stamp stamp, const MeshPeriodStatistics& s) override {
    EXPECT_TRUE(stamp == s.end);
    out.push_back(s);
  }
};

constexpr double kRate = 1000.0;        // [Hz] output samples
constexpr double kMesh = 1000.0 / 3.0;  // [Hz] three samples per period: phases 0, 1/3, 2/3
constexpr double kBaseRadius = 0.02;    // [m]
constexpr double kTorque = 0.1;         // [N*m]

struct Fixture {
  DynamicsEstimator dynamics{test::seedServo(), {1e8, 1e8}, kRate};
  MeshPeriodStage stage{dynamics, kBaseRadius};
  const MeshPeriodCounters& counters = stage.counters();
  Blocks sink;
  /// Sample k of a steady run at `sign` x kMesh: TE and force alternate about their means.
  void feed(int k, double sign = 1.0) {
    DynamicsSample s;
    const int turn_third = ((static_cast<int>(sign) * k) % 3 + 3) % 3;
    s.phase = turn_third / 3.0;
    s.dynamic_te = 1e-6 + (k % 2 ? 1e-8 : -1e-8);
    s.mesh_force = kTorque / kBaseRadius + (k % 2 ? 1.0 : -1.0);
    s.torque = kTorque;
    const Stamp stamp = test::stampAt(k / kRate);
    s.t = stamp.toSec();
    stage.sample(stamp, s, sign * kMesh, sink);
  }
};

}  // namespace

TEST(MeshPeriodStage, ABlockOfWholePeriodsClosesWhereThePhaseSays) {
  Fixture f;
  ASSERT_DOUBLE_EQ(f.dynamics.outputInterval(), 1.0 / kRate);
  for (int k = 0; k <= 24; ++k) f.feed(k);
  // periods = ceil(10 x 1 ms x 333 Hz) = 4: 12 samples a block, the first starting on the switch at
  // k = 0.
  ASSERT_EQ(f.sink.out.size(), 2u);
  const MeshPeriodStatistics& b = f.sink.out[0];
  EXPECT_EQ(b.periods, 4u);
  EXPECT_EQ(b.samples, 12u);
  EXPECT_TRUE(b.start == test::stampAt(0.0));
  EXPECT_TRUE(b.end == test::stampAt(0.012));
  EXPECT_NEAR(b.duration, 0.012, 1e-12);
  EXPECT_NEAR(b.mesh_frequency, kMesh, 1e-6);
  EXPECT_NEAR(b.torque, kTorque, 1e-15);
  // The state's velocity does not change: the mean mesh force is T / r_b,p exactly.
  EXPECT_DOUBLE_EQ(b.mesh_force_mean, kTorque / kBaseRadius);
  EXPECT_NEAR(b.te_mean, 1e-6, 1e-18);  // the trapezoid of an alternating signal over an even count
  EXPECT_NEAR(b.te_peak_to_peak, 2e-8, 1e-20);
  EXPECT_NEAR(b.mesh_force_peak_to_peak, 2.0, 1e-9);
  EXPECT_GT(b.te_rms, 0.0);
  EXPECT_EQ(f.counters.mesh_period_stats_out, 2u);
}

TEST(MeshPeriodStage, ARestartDropsTheRunningBlock) {
  Fixture f;
  for (int k = 0; k <= 10; ++k) f.feed(k);
  f.stage.restart();
  // From k = 11 (phase 2/3) the next block starts at the boundary at k = 12 and closes 12 later.
  for (int k = 11; k <= 23; ++k) f.feed(k);
  EXPECT_TRUE(f.sink.out.empty());
  f.feed(24);
  ASSERT_EQ(f.sink.out.size(), 1u);
  EXPECT_TRUE(f.sink.out[0].start == test::stampAt(0.012));
}

TEST(MeshPeriodStage, ASampleThatDoesNotMoveForwardIsSkipped) {
  Fixture f;
  for (int k = 0; k <= 5; ++k) f.feed(k);
  f.feed(5);  // the same stamp again
  for (int k = 6; k <= 12; ++k) f.feed(k);
  ASSERT_EQ(f.sink.out.size(), 1u);
  EXPECT_EQ(f.sink.out[0].samples, 12u);
}

TEST(MeshPeriodStage, InReverseThePeriodsCountBackward) {
  Fixture f;
  for (int k = 0; k <= 14; ++k) f.feed(k, -1.0);
  ASSERT_EQ(f.sink.out.size(), 1u);
  EXPECT_EQ(f.sink.out[0].periods, 4u);
  EXPECT_NEAR(f.sink.out[0].mesh_frequency, -kMesh, 1e-6);
}

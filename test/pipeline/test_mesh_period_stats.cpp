// Per-mesh-period statistics of the dynamic TE and the mesh force (RigPipeline,
// MeshPeriodStatistics): at 1000 rpm the 1 kHz output grid samples the 333 Hz mesh of the seed (20
// teeth) at three phases, one of them on the tooth switch, so the samples' mean of the mesh force
// is far off the true mean T / r_b,p; the per-period mean is not. Periods are counted from the mesh
// phase, also through a reversal.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

// Its calibration: block plays no part here (no encoders but in the reversal, which has no gear
// joint).
const RigConfig& rig() { return test::seedServo(); }
Stamp at(double seconds) { return test::stampAt(seconds); }
constexpr double kTorque = 0.1;  // [N*m] seed 000 Table 1
constexpr int kZp = 20;

struct Recorder : PipelineSink {
  std::vector<DynamicsSample> te;
  std::vector<MeshPeriodStatistics> blocks;
  std::vector<Stamp> stamps;
  void transmissionError(Stamp, const DynamicsSample& s, const SampleContext&) override {
    te.push_back(s);
  }
  void meshPeriod(Stamp stamp, const MeshPeriodStatistics& s) override {
    EXPECT_TRUE(stamp == s.end);
    stamps.push_back(stamp);
    blocks.push_back(s);
  }
};

/// Constant torque inputs every millisecond for `duration` at the nominal speed (no encoders).
void runNominal(RigPipeline& p, Recorder& r, double duration) {
  for (int k = 0; k * 1e-3 <= duration + 1e-12; ++k) {
    ASSERT_EQ(p.torque(at(1e-3 * k), kTorque, r), InputOutcome::kAccepted)
        << p.counters().last_event;
  }
}

bool finite(const MeshPeriodStatistics& s) {
  for (double v : {s.te_mean, s.te_rms, s.te_peak_to_peak, s.mesh_force_mean, s.mesh_force_rms,
                   s.mesh_force_peak_to_peak, s.mesh_frequency, s.torque, s.duration}) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

constexpr double kSettle = 0.3;  // [s] past the restart transient

}  // namespace

TEST(MeshPeriodStatistics, MeshForceMeanIsTOverBaseRadiusWhereTheSampleMeanIsNot) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  runNominal(p, r, 1.3);
  const double r_b = p.estimator().mesh().geometry().baseRadius(0);
  EXPECT_NEAR(r_b, 5.638e-3, 1e-3 * 5.638e-3);  // seed 000: r_b,p = r_p cos(20 deg)
  const double truth = kTorque / r_b;           // 17.7 N
  EXPECT_NEAR(truth, 0.1 / 5.638e-3, 2e-3 * truth);

  // The samples' mean over whole periods after the transient (3 samples per mesh period).
  double sum = 0.0;
  int n = 0;
  for (const DynamicsSample& s : r.te) {
    if (s.t - at(0).toSec() > kSettle && n < 900) {
      sum += s.mesh_force;
      ++n;
    }
  }
  ASSERT_EQ(n, 900);
  const double sample_mean = sum / n;
  EXPECT_GT(std::abs(sample_mean / truth - 1.0), 0.05)
      << "the grid no longer aliases the tooth switch";

  const double mesh_frequency = kZp * 1000.0 / 60.0;  // 333.3 Hz
  int checked = 0;
  double worst = 0.0, sum_block = 0.0;
  ASSERT_FALSE(r.blocks.empty());
  EXPECT_EQ(p.counters().mesh_period_stats_out, r.blocks.size());
  for (const MeshPeriodStatistics& b : r.blocks) {
    ASSERT_TRUE(finite(b));
    if (b.start.toSec() - at(0).toSec() < kSettle) continue;
    // ceil(10 x 1 ms x 333.3 Hz) = 4 periods of 3 samples.
    EXPECT_EQ(b.periods, 4u);
    EXPECT_EQ(b.samples, 12u);
    EXPECT_NEAR(b.duration, 4.0 / mesh_frequency, 1e-9);
    EXPECT_NEAR(b.mesh_frequency, mesh_frequency, 1e-3 * mesh_frequency);
    EXPECT_NEAR(b.torque, kTorque, 1e-12);
    worst = std::max(worst, std::abs(b.mesh_force_mean / truth - 1.0));
    sum_block += b.mesh_force_mean;
    EXPECT_GT(b.mesh_force_peak_to_peak, 0.0);
    EXPECT_GT(b.te_mean, 0.0);
    ++checked;
  }
  EXPECT_GT(checked, 75);  // 1 s / 12 ms
  EXPECT_LT(worst, 0.01);
  std::printf(
      "mesh force [N]: T/r_b = %.4f, plain mean of %d samples = %.4f (%+.1f %%), per-period means "
      "within "
      "%.3f %% (average %.4f) over %d blocks\n",
      truth, n, sample_mean, 100.0 * (sample_mean / truth - 1.0), 100.0 * worst,
      sum_block / checked, checked);
}

TEST(MeshPeriodStatistics, TeMeanConvergesToAFineGridsMean) {
  // The reference: the samples' mean over 90 whole periods of a 90-samples-per-period grid (30
  // kHz). The trapezoid of the dynamic TE converges with the samples per period; at 3 per period (1
  // kHz) it is off by ~14 % of this small mean (the TE settles within a fraction of a sample
  // interval after each tooth switch, a near-jump that 3 phases cannot place): the documented limit
  // of te_mean. The per-period mesh force mean is exact at any grid (momentum balance), while the
  // fine grid's own sample mean of the force is still biased by its samples on the switch.
  auto run = [](double rate, Recorder& r) {
    PipelineOptions o;
    o.output_rate = rate;
    RigPipeline p(rig(), o);
    runNominal(p, r, 0.6);
    return kTorque / p.estimator().mesh().geometry().baseRadius(0);
  };
  Recorder coarse, medium, fine;
  const double truth = run(1000.0, coarse);
  run(10000.0, medium);
  run(30000.0, fine);
  double te = 0.0, force = 0.0;
  int n = 0;
  const double t0 = at(0).toSec() + kSettle;
  for (const DynamicsSample& s : fine.te) {
    if (s.t > t0 && n < 90 * 90) {  // 90 whole periods
      te += s.dynamic_te;
      force += s.mesh_force;
      ++n;
    }
  }
  ASSERT_EQ(n, 90 * 90);
  te /= n;
  force /= n;
  EXPECT_NEAR(force, truth, 1e-2 * truth);
  auto worst = [&](const Recorder& r, double MeshPeriodStatistics::*field, double reference) {
    double w = 0.0;
    for (const MeshPeriodStatistics& b : r.blocks) {
      if (b.start.toSec() >= t0) w = std::max(w, std::abs(b.*field / reference - 1.0));
    }
    return w;
  };
  // The fine grid's own blocks: 1 period of 90 samples (ceil(10 / 90)).
  ASSERT_FALSE(fine.blocks.empty());
  EXPECT_EQ(fine.blocks.back().periods, 1u);
  EXPECT_EQ(fine.blocks.back().samples, 90u);
  const double te_1k = worst(coarse, &MeshPeriodStatistics::te_mean, te);
  const double te_10k = worst(medium, &MeshPeriodStatistics::te_mean, te);
  const double te_30k = worst(fine, &MeshPeriodStatistics::te_mean, te);
  EXPECT_LT(te_30k, 5e-3);
  EXPECT_LT(te_10k, 0.05);
  EXPECT_LT(te_1k, 0.2);
  for (const Recorder* r : {&coarse, &medium, &fine})
    EXPECT_LT(worst(*r, &MeshPeriodStatistics::mesh_force_mean, truth), 1e-3);
  std::printf(
      "dynamic TE mean [m]: 30 kHz samples %.6e; per-period te_mean off by at most %.2f %% (1 "
      "kHz), %.2f %% "
      "(10 kHz), %.3f %% (30 kHz); 30 kHz samples' mesh force mean %.4f N (%+.2f %%), per-period "
      "exact\n",
      te, 100.0 * te_1k, 100.0 * te_10k, 100.0 * te_30k, force, 100.0 * (force / truth - 1.0));
}

TEST(MeshPeriodStatistics, ReversalGivesFiniteStatsInBothDirections) {
  // 1000 rpm down through zero to -1000 rpm in 0.4 s, encoder readings every millisecond
  // (test_rig_pipeline_motion.cpp's feeding), torque held.
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  const double w0 = 1000.0 / 60.0 * kTwoPi, a = -2.0 * w0 / 0.4;
  auto angle = [&](double t) { return w0 * t + 0.5 * a * t * t; };
  auto speed = [&](double t) { return w0 + a * t; };
  for (int k = 0; k * 1e-3 < 0.6; ++k) {
    const double t = 1e-3 * k, tr = std::min(t + 3e-4, 0.4);
    ASSERT_EQ(p.torque(at(t), kTorque, r), InputOutcome::kAccepted);
    MotionInput in;
    in.pinion_angle = std::remainder(angle(tr) + speed(tr) * (t + 3e-4 - tr), kTwoPi);
    in.pinion_velocity = speed(tr);
    ASSERT_EQ(p.motion(at(t + 3e-4), in, r), InputOutcome::kAccepted) << p.counters().last_event;
  }
  ASSERT_FALSE(r.blocks.empty());
  int forward = 0, backward = 0;
  for (const MeshPeriodStatistics& b : r.blocks) {
    ASSERT_TRUE(finite(b));
    EXPECT_GE(b.periods, 1u);
    EXPECT_GT(b.samples, 0u);
    EXPECT_GT(b.duration, 0.0);
    if (b.mesh_frequency > 0.0) ++forward;
    if (b.mesh_frequency < 0.0) ++backward;
  }
  EXPECT_GT(forward, 5);
  EXPECT_GT(backward, 5);
  // The last blocks run at -1000 rpm: -333 Hz, 4 periods each.
  EXPECT_NEAR(r.blocks.back().mesh_frequency, -kZp * 1000.0 / 60.0, 1e-3 * kZp * 1000.0 / 60.0);
  EXPECT_EQ(r.blocks.back().periods, 4u);
  for (const DynamicsSample& s : r.te)
    ASSERT_TRUE(std::isfinite(s.dynamic_te) && std::isfinite(s.mesh_force));
}

TEST(MeshPeriodStatistics, ResetRestartsTheAccumulation) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  runNominal(p, r, 0.1);
  const std::size_t before = r.blocks.size();
  ASSERT_GT(before, 0u);
  p.reset("test");
  // The dynamics restart at the next input, 0.5 s on: no block spans the reset.
  for (int k = 0; k < 100; ++k)
    ASSERT_EQ(p.torque(at(0.6 + 1e-3 * k), kTorque, r), InputOutcome::kAccepted);
  ASSERT_GT(r.blocks.size(), before);
  for (std::size_t i = before; i < r.blocks.size(); ++i) {
    EXPECT_GE(r.blocks[i].start.toSec(), at(0.6).toSec() - 1e-9);
    EXPECT_EQ(r.blocks[i].periods, 4u);
  }
}

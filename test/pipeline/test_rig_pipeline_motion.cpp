// The rig's measured motion as a pipeline input (the encoders and own-stamp rules,
// docs/ros_api.md): the mesh phase follows the encoder angle through speed changes and reversal,
// the velocity is differentiated when absent, and every refusal, drop, time-out and gear-ratio
// mismatch is counted.
#include <gtest/gtest.h>

#include <cmath>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() { return test::seedServo(); }
Stamp at(double seconds) { return test::stampAt(seconds); }
constexpr int kZp = 20, kZg = 40;  // seed 000 Table 1

struct Recorder : PipelineSink {
  std::vector<DynamicsSample> te;
  std::vector<double> drawn_angle;  ///< [rad] SampleContext::pinion_angle, what the tf frames draw
  void transmissionError(Stamp stamp, const DynamicsSample& s,
                         const SampleContext& context) override {
    EXPECT_EQ(s.t, stamp.toSec());
    EXPECT_TRUE(s.state.allFinite() && std::isfinite(s.dynamic_te) && std::isfinite(s.mesh_force));
    te.push_back(s);
    drawn_angle.push_back(context.pinion_angle);
  }
};

/// A motion profile: pinion angle [rad] and speed [rad/s] at t [s].
struct Profile {
  std::function<double(double)> angle, speed;
};

/// Torque and encoder readings at 1 kHz, the readings 0.3 ms after each torque input (off the
/// grid).
void drive(RigPipeline& p, Recorder& r, const Profile& m, double duration, double torque,
           bool velocity = true) {
  for (int k = 0; k * 1e-3 < duration; ++k) {
    const double t = 1e-3 * k;
    ASSERT_EQ(p.torque(at(t), torque, r), InputOutcome::kAccepted);
    MotionInput in;
    in.pinion_angle = std::remainder(m.angle(t + 3e-4), kTwoPi);  // an encoder that wraps at +-pi
    if (velocity) in.pinion_velocity = m.speed(t + 3e-4);
    in.gear_angle =
        std::remainder(-static_cast<double>(kZp) / kZg * m.angle(t + 3e-4) + 0.25, kTwoPi);
    ASSERT_EQ(p.motion(at(t + 3e-4), in, r), InputOutcome::kAccepted) << p.counters().last_event;
  }
}

/// The mesh phase of a pinion angle (gear_geometry.cpp SpurGearGeometry::phase), plus an offset.
double phaseOf(double angle, double offset = 0.0) {
  const double turns = angle * kZp / kTwoPi + offset;
  return turns - std::floor(turns);
}
double phaseDistance(double a, double b) { return std::abs(std::remainder(a - b, 1.0)); }

/// The encoders rule's pinion angle at t: the last reading (at k ms + 0.3 ms, see drive)
/// extrapolated at its speed.
double extrapolated(const Profile& m, double t) {
  const double t_r = std::floor((t - 3e-4) / 1e-3 + 1e-9) * 1e-3 + 3e-4;
  return m.angle(t_r) + m.speed(t_r) * (t - t_r);
}
/// Output sample i is at (i + 1) ms: the dynamics start at the first torque input (t = 0).
double sampleTime(std::size_t i) { return 1e-3 * static_cast<double>(i + 1); }

}  // namespace

TEST(RigPipelineMotion, PhaseFollowsTheEncoderThroughARunUp) {
  // 300 -> 3000 rpm in 0.2 s; offset 0.125 of a mesh period. Between readings the phase is
  // extrapolated at the last reading's speed (the encoders rule): checked to 1e-6 of a period
  // against that rule, and to a dt^2 / 2 z_p / 2 pi = 1.1e-3 of a period against the true angle (a
  // = 1414 rad/s^2, dt = 0.7 ms from the reading to the sample).
  PipelineOptions o;
  o.mesh_phase_offset = 0.125;
  RigPipeline p(rig(), o);
  const double a = (3000.0 - 300.0) / 60.0 * kTwoPi / 0.2, w0 = 300.0 / 60.0 * kTwoPi;
  const Profile m{[&](double t) { return w0 * t + 0.5 * a * t * t; },
                  [&](double t) { return w0 + a * t; }};
  Recorder r;
  drive(p, r, m, 0.2, 0.1);
  EXPECT_STREQ(p.phaseSource(), "encoders");
  ASSERT_GT(r.te.size(), 190u);
  for (std::size_t i = 1; i < r.te.size(); ++i) {
    const double t = sampleTime(i);
    EXPECT_LT(phaseDistance(r.te[i].phase, phaseOf(extrapolated(m, t), 0.125)), 1e-6)
        << "sample " << i;
    EXPECT_LT(phaseDistance(r.te[i].phase, phaseOf(m.angle(t), 0.125)), 1.2e-3) << "sample " << i;
  }
  const PipelineCounters& c = p.counters();
  EXPECT_EQ(c.accepted_motion, 200u);
  EXPECT_EQ(c.rejected_motion + c.dropped_motion + c.motion_timeouts + c.gear_ratio_mismatches, 0u);
  EXPECT_EQ(p.dynamics()->work().fallback_intervals, 0);
  // The stiffness estimate's mesh phase follows the same angle.
  EXPECT_LT(
      phaseDistance(p.estimator().current().mesh.phase, phaseOf(extrapolated(m, 0.199), 0.125)),
      1e-6);
  // The angle the tf frames draw is the encoders' (extrapolated, as the phase), not the offset one
  // the mesh phase is computed from: 0.125 of a mesh period is 2.2 degrees of the pinion.
  ASSERT_EQ(r.drawn_angle.size(), r.te.size());
  for (std::size_t i = 1; i < r.te.size(); ++i) {
    EXPECT_LT(std::abs(std::remainder(r.drawn_angle[i] - extrapolated(m, sampleTime(i)), kTwoPi)),
              1e-9)
        << "sample " << i;
  }
}

TEST(RigPipelineMotion, VelocityDifferentiatedWhenAbsent) {
  RigPipeline p(rig(), PipelineOptions{});
  const double w = 2000.0 / 60.0 * kTwoPi;  // 0.21 rad per reading: unwrapped from +-pi
  const Profile m{[&](double t) { return w * t; }, [&](double) { return w; }};
  Recorder r;
  drive(p, r, m, 0.1, 0.1, false);
  // A constant speed differentiates exactly; the phase then matches to rounding.
  for (std::size_t i = 1; i < r.te.size(); ++i)
    EXPECT_LT(phaseDistance(r.te[i].phase, phaseOf(m.angle(sampleTime(i)))),
              2e-6);  // 1e-6: a sample on a switch reads its right limit
  EXPECT_NEAR(p.dynamics()->meshFrequency(), kZp * w / kTwoPi, 1e-6);
}

TEST(RigPipelineMotion, ReversalThroughStandstillKeepsTheDriveFlankLoaded) {
  // +1000 rpm through 0 to -1000 rpm and back (a cosine in 0.4 s), positive torque: the torque's
  // sign selects the loaded flank, not the direction of rotation; nothing non-finite.
  RigPipeline p(rig(), PipelineOptions{});
  const double w = 1000.0 / 60.0 * kTwoPi, om = kTwoPi / 0.4;
  const Profile m{[&](double t) { return w / om * std::sin(om * t); },
                  [&](double t) { return w * std::cos(om * t); }};
  Recorder r;
  drive(p, r, m, 0.4, 0.1);
  ASSERT_GT(r.te.size(), 390u);
  for (const DynamicsSample& s : r.te) EXPECT_TRUE(s.drive_flank_loaded && s.back_flank_loaded);
  for (std::size_t i = 1; i < r.te.size(); ++i)
    EXPECT_LT(phaseDistance(r.te[i].phase, phaseOf(extrapolated(m, sampleTime(i)))), 1e-6);
  EXPECT_LT(p.dynamics()->meshFrequency(), 0.0 + kZp * w / kTwoPi);
}

TEST(RigPipelineMotion, EveryRuleCounted) {
  PipelineOptions o;
  o.motion_timeout = 0.05;
  RigPipeline p(rig(), o);
  Recorder r;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_EQ(p.torque(at(0.0), 0.1, r), InputOutcome::kAccepted);
  EXPECT_STREQ(p.phaseSource(), "nominal");
  EXPECT_FALSE(p.encoderSilence(at(0.0)).has_value()) << "no encoders yet";
  MotionInput good;
  good.pinion_angle = 0.0;
  good.pinion_velocity = 10.0;
  good.gear_angle = 0.0;
  ASSERT_EQ(p.motion(at(0.001), good, r, {"/rig", 1, ""}), InputOutcome::kAccepted);
  // NaN position, absurd velocity: refused naming the field; the state keeps the last reading.
  MotionInput bad = good;
  bad.pinion_angle = nan;
  EXPECT_EQ(p.motion(at(0.002), bad, r, {"/rig", 2, ""}), InputOutcome::kInvalidValue);
  EXPECT_NE(p.counters().last_event.find("pinion position"), std::string::npos)
      << p.counters().last_event;
  bad = good;
  bad.pinion_velocity = 2e4;
  EXPECT_EQ(p.motion(at(0.003), bad, r, {"/rig", 3, ""}), InputOutcome::kInvalidValue);
  EXPECT_NE(p.counters().last_event.find("pinion velocity"), std::string::npos);
  // Out of order, zero stamp, missing joint (the caller's refusal), and two numbered messages lost.
  EXPECT_EQ(p.motion(at(0.0005), good, r, {"/rig", 4, ""}), InputOutcome::kOutOfOrder);
  EXPECT_EQ(p.motion(Stamp{0}, good, r, {"/rig", 5, ""}), InputOutcome::kZeroStamp);
  EXPECT_EQ(p.motionRefused(at(0.004), "no joint named 'pinion' (~pinion_joint)", {"/rig", 6, ""}),
            InputOutcome::kInvalidValue);
  good.pinion_angle = 0.04;
  good.gear_angle = -0.5 * 0.04;
  ASSERT_EQ(p.motion(at(0.005), good, r, {"/rig", 9, ""}), InputOutcome::kAccepted);
  // The gear slips by 0.05 rad against -(z_p/z_g) x pinion angle: reported once.
  good.pinion_angle = 0.05;
  good.gear_angle = -0.5 * 0.05 + 0.05;
  ASSERT_EQ(p.motion(at(0.006), good, r, {"/rig", 10, ""}), InputOutcome::kAccepted);
  good.pinion_angle = 0.06;
  good.gear_angle = -0.5 * 0.06 + 0.05;
  ASSERT_EQ(p.motion(at(0.007), good, r, {"/rig", 11, ""}), InputOutcome::kAccepted);
  // With every input stopped the time-out waits for the next input's stamp: the source still says
  // encoders, and the age of the last reading (at 0.007 s) on a clock says how stale that is.
  EXPECT_STREQ(p.phaseSource(), "encoders");
  ASSERT_TRUE(p.encoderSilence(at(0.09)).has_value());
  EXPECT_NEAR(*p.encoderSilence(at(0.09)), 0.083, 1e-12);
  // Encoders silent for more than 0.05 s: back to the nominal speed, counted.
  ASSERT_EQ(p.torque(at(0.1), 0.1, r), InputOutcome::kAccepted);
  EXPECT_STREQ(p.phaseSource(), "nominal (encoders timed out)");
  EXPECT_FALSE(p.encoderSilence(at(0.1)).has_value()) << "the encoders no longer drive the phase";
  EXPECT_NEAR(p.dynamics()->meshFrequency(), 1000.0 / 60.0 * kZp,
              1e-9);  // seed_servo.yaml: 1000 rpm
  const PipelineCounters& c = p.counters();
  EXPECT_EQ(c.accepted_motion, 4u);
  EXPECT_EQ(c.rejected_motion, 5u);
  EXPECT_EQ(c.invalid_values, 3u);
  EXPECT_EQ(c.out_of_order, 1u);
  EXPECT_EQ(c.zero_stamps, 1u);
  EXPECT_EQ(c.dropped_motion, 2u);  // seq 7 and 8 never arrived
  EXPECT_EQ(c.gear_ratio_mismatches, 1u);
  EXPECT_EQ(c.motion_timeouts, 1u);
  bool listed = false;
  for (const auto& [name, value] : namedCounters(c))
    listed |= name == "dropped_joint_states" && value == 2u;
  EXPECT_TRUE(listed);
}

TEST(RigPipelineMotion, ReplayOfTheSameInputsIsBitIdentical) {
  auto run = [] {
    RigPipeline p(rig(), PipelineOptions{});
    Recorder r;
    const double a = 3e3;
    drive(p, r,
          Profile{[&](double t) { return 50.0 * t + 0.5 * a * t * t; },
                  [&](double t) { return 50.0 + a * t; }},
          0.1, 0.1);
    return r.te;
  };
  const auto first = run(), second = run();
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(first[i].dynamic_te, second[i].dynamic_te);
    EXPECT_EQ(first[i].phase, second[i].phase);
  }
}

// Fuzz findings (docs/reliability.md): an encoder count near DBL_MAX overflowed z_p theta into a
// NaN mesh phase; a differentiated speed had no bound; an advance across millions of slices
// stalled.
TEST(RigPipelineMotion, HugeEncoderCountsKeepTheirPhase) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  ASSERT_EQ(p.torque(at(0.0), 0.1, r), InputOutcome::kAccepted);
  MotionInput m;
  m.pinion_angle = 1e308;  // z_p x this overflows a double; only the angle modulo a turn matters
  m.pinion_velocity = 100.0;
  ASSERT_EQ(p.motion(at(0.001), m, r), InputOutcome::kAccepted) << p.counters().last_event;
  ASSERT_EQ(p.torque(at(0.002), 0.1, r), InputOutcome::kAccepted) << p.counters().last_event;
  EXPECT_LT(
      phaseDistance(r.te.back().phase, phaseOf(std::remainder(1e308, kTwoPi) + 100.0 * 0.001)),
      1e-9);
  EXPECT_EQ(p.counters().dynamics_errors, 0u);
}

TEST(RigPipelineMotion, DifferentiatedSpeedBeyondTheBoundIsRefused) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  MotionInput m;
  m.pinion_angle = 0.0;
  ASSERT_EQ(p.motion(at(0.001), m, r), InputOutcome::kAccepted);
  m.pinion_angle = 1.0;  // 1 rad in 10 us: 1e5 rad/s, an encoder jump
  EXPECT_EQ(p.motion(at(0.00101), m, r), InputOutcome::kInvalidValue);
  EXPECT_NE(p.counters().last_event.find("pinion position"), std::string::npos)
      << p.counters().last_event;
  m.pinion_angle = 0.001;  // 100 rad/s from the last accepted reading: fine
  EXPECT_EQ(p.motion(at(0.00102), m, r), InputOutcome::kAccepted) << p.counters().last_event;
}

TEST(RigPipelineMotion, AnAdvanceAcrossTooManySlicesRestartsInsteadOfStalling) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  ASSERT_EQ(p.torque(at(0.0), 0.1, r), InputOutcome::kAccepted);
  MotionInput m;
  m.pinion_angle = 0.0;
  m.pinion_velocity = 1e4;  // 95,500 rpm: 31.8 kHz mesh, 8.2e6 slices per second
  ASSERT_EQ(p.motion(at(0.0005), m, r), InputOutcome::kAccepted);
  // 0.5 s later (inside ~max_gap): 4e6 slices, more than DynamicsEstimator::kMaxSlicesPerAdvance.
  EXPECT_EQ(p.torque(at(0.5), 0.1, r), InputOutcome::kAccepted);
  EXPECT_GE(p.counters().dynamics_errors, 1u);
  EXPECT_NE(p.counters().last_event.find("phase slices"), std::string::npos)
      << p.counters().last_event;
  EXPECT_TRUE(p.dynamics()->started());  // restarted at that input
}

// The calibration rule pairs each reading with the torque held at it: the last accepted torque
// input, whether or not it (re)started the dynamics. A torque of 0.2 N*m (above the seed's
// ~baseline_torque, 0.05 N*m: config/gearboxes/seed_servo.yaml) that starts the stopped dynamics
// makes the readings after it a loaded stretch; after a pause longer than ~max_gap (1 s) a torque
// of 0 N*m restarts them and the readings after it are unloaded.
TEST(RigPipelineMotion, TheTorqueThatRestartsTheDynamicsIsTheHeldTorque) {
  RigPipeline p(rig(), PipelineOptions{});
  ASSERT_NE(p.calibrator(), nullptr);
  Recorder r;
  const double w = 120.0 / 60.0 * kTwoPi;  // [rad/s]
  auto readings = [&](double from, double to) {
    for (double t = from; t < to; t += 1e-3) {
      MotionInput in;
      in.pinion_angle = std::remainder(w * t, kTwoPi);
      in.pinion_velocity = w;
      in.gear_angle = std::remainder(-static_cast<double>(kZp) / kZg * w * t, kTwoPi);
      ASSERT_EQ(p.motion(at(t), in, r), InputOutcome::kAccepted) << p.counters().last_event;
    }
  };
  ASSERT_EQ(p.torque(at(0.0), 0.2, r), InputOutcome::kAccepted);  // starts the dynamics
  readings(3e-4, 0.3);
  const CalibrationProgress loaded = p.calibrator()->progress();
  EXPECT_EQ(loaded.unloaded.readings, 0);
  EXPECT_GT(loaded.loaded.readings, 250);
  EXPECT_NEAR(loaded.loaded.torque, 0.2, 1e-12);
  // Every input pauses for 1.7 s: the gap rule stops the dynamics; the next torque restarts them.
  ASSERT_EQ(p.torque(at(2.0), 0.0, r), InputOutcome::kAccepted);
  EXPECT_EQ(p.counters().gap_restarts, 1u);
  readings(2.0003, 2.3);
  EXPECT_GT(p.calibrator()->progress().unloaded.readings, 250);
}

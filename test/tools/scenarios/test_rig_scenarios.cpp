// The rig scenarios' encoder readings (src/tools/scenarios/rig_scenarios.hpp): joint events at
// their rate, on the 2^20-count grid, the gear at -(z_p / z_g) of the pinion (motion.hpp's sign
// convention), the speed scenarios' speeds and angles against their closed forms (ramp: omega = s0
// + (s1 - s0) t / T, theta = s0 t + (s1 - s0) t^2 / (2 T); reversal: omega = s cos(2 pi t / T),
// theta = s T sin(2 pi t / T) / (2 pi)), and the older scenarios' torque and preload events
// unchanged by the readings.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "scenarios/rig_encoder.hpp"
#include "scenarios/rig_scenarios.hpp"

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() {  // seed 000 Table 1: z_p = 20, z_g = 40, 1000 rpm, 0.1 N*m
  static const RigConfig r =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  return r;
}

constexpr double kRpm = kTwoPi / 60.0;         // 1 rpm in rad/s
constexpr double kCount = kTwoPi / 1048576.0;  // one encoder count: 2 pi / 2^20 rad
constexpr double kRatio = 20.0 / 40.0;         // z_p / z_g of the seed pair

std::vector<RigEvent> scenario(const std::string& name, double joint_rate = 1000.0,
                               bool velocity = true) {
  ScenarioSpec spec;
  spec.name = name;
  spec.joint_rate = joint_rate;
  spec.joint_velocity = velocity;
  return makeScenario(rig(), spec);
}

std::vector<RigEvent> joints(const std::vector<RigEvent>& events) {
  std::vector<RigEvent> out;
  for (const RigEvent& e : events) {
    if (e.motion) out.push_back(e);
  }
  return out;
}

/// True if x is an integer multiple of one count (to the rounding of x / count).
bool onTheGrid(double x) {
  const double counts = x / kCount;
  return std::abs(counts - std::round(counts)) <= 1e-9 * std::max(1.0, std::abs(counts));
}

/// The checks every speed scenario shares: 2000 readings at 1 kHz from t = 0; both angles on the
/// grid and within half a count of the closed-form angle; the gear at -z_p / z_g of the pinion;
/// the speed given by omega(t). `theta` and `omega` are the closed forms [rad, rad/s].
template <typename Theta, typename Omega>
void expectReadings(const std::string& name, Theta theta, Omega omega) {
  SCOPED_TRACE(name);
  const std::vector<RigEvent> j = joints(scenario(name));
  ASSERT_EQ(j.size(), 2000u);  // 2 s at 1000 Hz
  for (std::size_t k = 0; k < j.size(); ++k) {
    const RigEvent& e = j[k];
    ASSERT_NEAR(e.t, k * 1e-3, 1e-12);
    ASSERT_FALSE(e.torque);
    ASSERT_TRUE(e.preload.empty());
    const MotionInput& m = *e.motion;
    ASSERT_TRUE(m.gear_angle && m.pinion_velocity && e.gear_velocity);
    ASSERT_TRUE(onTheGrid(m.pinion_angle)) << e.t << ": " << m.pinion_angle;
    ASSERT_TRUE(onTheGrid(*m.gear_angle)) << e.t << ": " << *m.gear_angle;
    ASSERT_LE(std::abs(m.pinion_angle - theta(e.t)), 0.5 * kCount + 1e-9) << e.t;
    ASSERT_LE(std::abs(*m.gear_angle + kRatio * theta(e.t)), 0.5 * kCount + 1e-9) << e.t;
    // Both quantised: theta_g + (z_p / z_g) theta_p within half a count of each.
    ASSERT_LE(std::abs(*m.gear_angle + kRatio * m.pinion_angle),
              0.5 * kCount * (1.0 + kRatio) + 1e-12)
        << e.t;
    ASSERT_NEAR(*m.pinion_velocity, omega(e.t), 1e-9 * (1.0 + std::abs(omega(e.t)))) << e.t;
    ASSERT_EQ(*e.gear_velocity, -kRatio * *m.pinion_velocity) << e.t;
  }
}

std::vector<RigEvent> torqueAndPreload(const std::vector<RigEvent>& events) {
  std::vector<RigEvent> out;
  for (const RigEvent& e : events) {
    if (!e.motion) out.push_back(e);
  }
  return out;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }  // NaN == NaN too

}  // namespace

TEST(RigScenarios, EncoderQuantisationIsOnTheGridWithinHalfACount) {
  EXPECT_NEAR(kCount, 5.992112452678286e-06, 1e-20);
  for (double theta : {0.0, 1e-7, 3e-6, -3e-6, 1.0, -2.5, 628.3185307179587, 1e4}) {
    const double q = quantiseEncoderAngle(theta);
    EXPECT_TRUE(onTheGrid(q)) << theta;
    EXPECT_LE(std::abs(q - theta), 0.5 * kCount) << theta;
  }
  EXPECT_EQ(quantiseEncoderAngle(0.4 * kCount), 0.0);
  EXPECT_EQ(quantiseEncoderAngle(kPi), kPi);  // half a revolution is 2^19 counts
  EXPECT_EQ(quantiseEncoderAngle(-kTwoPi), -kTwoPi);
}

TEST(RigScenarios, RunUpGoesFrom0To6000Rpm) {
  const double T = 2.0, s1 = 6000.0 * kRpm;  // 628.3185 rad/s
  expectReadings(
      "run_up", [&](double t) { return s1 * t * t / (2.0 * T); },
      [&](double t) { return s1 * t / T; });
  const std::vector<RigEvent> j = joints(scenario("run_up"));
  EXPECT_EQ(*j.front().motion->pinion_velocity, 0.0);
  EXPECT_NEAR(*j.back().motion->pinion_velocity, 628.3185307179587 * 1.999 / 2.0,
              1e-9);  // last sample at T - 1 ms
  EXPECT_NEAR(*j.back().motion->pinion_velocity, 628.3185, 628.3185 * 1e-3 / T + 1e-4);
}

TEST(RigScenarios, CoastDownGoesFrom6000RpmTo0) {
  const double T = 2.0, s0 = 6000.0 * kRpm;
  expectReadings(
      "coast_down", [&](double t) { return s0 * t - s0 * t * t / (2.0 * T); },
      [&](double t) { return s0 - s0 * t / T; });
  const std::vector<RigEvent> j = joints(scenario("coast_down"));
  EXPECT_NEAR(*j.front().motion->pinion_velocity, 628.3185307179587, 1e-12);
  EXPECT_NEAR(*j.back().motion->pinion_velocity, 628.3185307179587 * 1e-3 / T,
              1e-9);  // last sample at T - 1 ms
  // Nearly stopped: the angle approaches s0 T / 2 = 628.3 rad (100 revolutions).
  EXPECT_NEAR(j.back().motion->pinion_angle, s0 * T / 2.0, s0 * 1e-6 / T + kCount);
}

TEST(RigScenarios, SpeedStepsDwellAtEachLevelWith50msRamps) {
  // Levels 500, 1000, 2000, 4000 rpm from 0, 0.5, 1, 1.5 s; each step a 50 ms ramp.
  const double levels[] = {500.0, 1000.0, 2000.0, 4000.0}, r = 0.05;
  auto omega = [&](double t) {
    double w = levels[0];
    for (int i = 1; i < 4; ++i) {
      const double start = 0.5 * i;
      if (t >= start + r)
        w = levels[i];
      else if (t >= start)
        w = levels[i - 1] + (levels[i] - levels[i - 1]) * (t - start) / r;
    }
    return w * kRpm;
  };
  // theta by hand: each finished dwell, each finished ramp at its mean speed, then the part in
  // progress.
  auto theta = [&](double t) {
    double a = 0.0, last = 0.0;
    for (int i = 1; i < 4 && t >= 0.5 * i; ++i) {
      const double start = 0.5 * i, ramp_end = std::min(t, start + r), tau = ramp_end - start;
      a += levels[i - 1] * kRpm * (start - last);
      a += levels[i - 1] * kRpm * tau + 0.5 * (levels[i] - levels[i - 1]) * kRpm * tau * tau / r;
      last = start + r;
      if (t < last) return a;
    }
    const int level = t < 0.5 ? 0 : std::min(3, static_cast<int>(t / 0.5));
    return a + levels[level] * kRpm * (t - last);
  };
  expectReadings("speed_steps", theta, omega);
  const std::vector<RigEvent> j = joints(scenario("speed_steps"));
  EXPECT_NEAR(*j[250].motion->pinion_velocity, 500.0 * kRpm, 1e-9);
  EXPECT_NEAR(*j[525].motion->pinion_velocity, 750.0 * kRpm, 1e-9);  // mid-ramp
  EXPECT_NEAR(*j[800].motion->pinion_velocity, 1000.0 * kRpm, 1e-9);
  EXPECT_NEAR(*j[1300].motion->pinion_velocity, 2000.0 * kRpm, 1e-9);
  EXPECT_NEAR(*j[1999].motion->pinion_velocity, 4000.0 * kRpm, 1e-9);
}

TEST(RigScenarios, ReverseCrossesZeroTo1000RpmBackwardsAndBack) {
  const double T = 2.0, s = 1000.0 * kRpm;
  expectReadings(
      "reverse", [&](double t) { return s * T * std::sin(kTwoPi * t / T) / kTwoPi; },
      [&](double t) { return s * std::cos(kTwoPi * t / T); });
  const std::vector<RigEvent> j = joints(scenario("reverse"));
  EXPECT_NEAR(*j[0].motion->pinion_velocity, s, 1e-12);
  EXPECT_NEAR(*j[1000].motion->pinion_velocity, -1000.0 * kRpm, 1e-9);  // -104.72 rad/s at T/2
  double lowest = 0.0;
  for (const RigEvent& e : j) lowest = std::min(lowest, *e.motion->pinion_velocity);
  EXPECT_NEAR(lowest, -104.71975511965977, 1e-9);
  // Zero at T/4 and 3T/4, with the sign changing there.
  for (std::size_t k : {500u, 1500u}) {
    EXPECT_NEAR(*j[k].motion->pinion_velocity, 0.0, 1e-12 * s) << k;
    EXPECT_LT(*j[k - 1].motion->pinion_velocity * *j[k + 1].motion->pinion_velocity, 0.0) << k;
  }
  // The angle turns back where the speed crosses zero: its peak s T / (2 pi) = 33.33 rad at T/4.
  EXPECT_NEAR(j[500].motion->pinion_angle, s * T / kTwoPi, kCount);
  EXPECT_LT(j[499].motion->pinion_angle,
            j[500].motion->pinion_angle);  // 1 ms off the peak: 1.6e-4 rad (27 counts) lower
  EXPECT_LT(j[501].motion->pinion_angle, j[500].motion->pinion_angle);
  // The torque keeps its sign (constant 0.1 N*m) while the speed reverses.
  for (const RigEvent& e : scenario("reverse")) {
    if (e.torque) {
      ASSERT_EQ(*e.torque, 0.1) << e.t;
    }
  }
}

TEST(RigScenarios, SpeedScenariosSendConstantTorqueAndOnePreload) {
  for (const char* name : {"run_up", "coast_down", "speed_steps", "reverse"}) {
    const std::vector<RigEvent> e = torqueAndPreload(scenario(name));
    ASSERT_EQ(e.size(), 2001u) << name;  // one preload, 2000 torque samples
    EXPECT_EQ(e[0].preload.size(), rig().bearings.size()) << name;
    for (std::size_t k = 1; k < e.size(); ++k) ASSERT_EQ(*e[k].torque, 0.1) << name;
  }
}

TEST(RigScenarios, OlderScenariosTurnAtTheNominalSpeed) {
  // dynamics.speed_rpm = 1000: theta = omega t, omega = 104.72 rad/s, for every one of them.
  const double w = 1000.0 * kRpm;
  for (const char* name : {"torque_ripple", "torque_steps", "preload_ramp", "speed_sweep"}) {
    SCOPED_TRACE(name);
    const std::vector<RigEvent> j = joints(scenario(name));
    ASSERT_EQ(j.size(), 2000u);
    for (std::size_t k : {0u, 1u, 999u, 1999u}) {
      EXPECT_NEAR(*j[k].motion->pinion_velocity, w, 1e-12);
      EXPECT_LE(std::abs(j[k].motion->pinion_angle - w * j[k].t), 0.5 * kCount);
      EXPECT_LE(std::abs(*j[k].motion->gear_angle + kRatio * w * j[k].t), 0.5 * kCount);
      EXPECT_EQ(j[k].stamp_offset, 0.0);
    }
  }
}

TEST(RigScenarios, TheReadingsLeaveTheTorqueAndPreloadEventsAsTheyWere) {
  for (const char* name :
       {"torque_ripple", "torque_steps", "preload_ramp", "speed_sweep", "faults"}) {
    SCOPED_TRACE(name);
    const std::vector<RigEvent> without = scenario(name, 0.0);
    for (const RigEvent& e : without) ASSERT_FALSE(e.motion);
    const std::vector<RigEvent> with = torqueAndPreload(scenario(name));
    ASSERT_EQ(with.size(), without.size());
    for (std::size_t k = 0; k < with.size(); ++k) {
      const RigEvent &a = with[k], &b = without[k];
      ASSERT_TRUE(sameBits(a.t, b.t)) << k;
      ASSERT_EQ(a.torque.has_value(), b.torque.has_value()) << k;
      if (a.torque) {
        ASSERT_TRUE(sameBits(*a.torque, *b.torque)) << k;
      }
      ASSERT_EQ(a.preload.size(), b.preload.size()) << k;
      for (std::size_t i = 0; i < a.preload.size(); ++i) {
        ASSERT_EQ(a.preload[i].name, b.preload[i].name);
        ASSERT_TRUE(sameBits(a.preload[i].axial_preload, b.preload[i].axial_preload)) << k;
      }
      ASSERT_EQ(a.zero_stamp, b.zero_stamp) << k;
      ASSERT_TRUE(sameBits(a.stamp_offset, b.stamp_offset)) << k;
      ASSERT_EQ(a.lost_before, b.lost_before) << k;
      ASSERT_EQ(a.frame_id, b.frame_id) << k;
    }
  }
  // The documented values at a few times (docs/tools.md), independent of the code above: 2000
  // torque samples plus the preloads (1 Hz over 2 s: 2; once; 10 Hz: 20; once) and 13 faults.
  EXPECT_EQ(scenario("torque_ripple", 0.0).size(), 2002u);
  EXPECT_EQ(scenario("torque_steps", 0.0).size(), 2001u);
  EXPECT_EQ(scenario("preload_ramp", 0.0).size(), 2020u);
  EXPECT_EQ(scenario("speed_sweep", 0.0).size(), 2001u);
  EXPECT_EQ(scenario("faults", 0.0).size(), 2015u);
  const std::vector<RigEvent> ripple = torqueAndPreload(scenario("torque_ripple"));
  EXPECT_EQ(*ripple[1].torque, 0.1);  // t = 0: sin 0 = 0, the mean
  // t = 1 ms: 0.1 (1 + 0.05 sin(2 pi 100 Hz t) + 0.02 sin(2 pi 200 Hz t)), 6th and 12th order of
  // 1000 rpm.
  EXPECT_NEAR(*ripple[2].torque,
              0.1 * (1 + 0.05 * std::sin(kTwoPi * 0.1) + 0.02 * std::sin(kTwoPi * 0.2)), 1e-15);
  const std::vector<RigEvent> steps = torqueAndPreload(scenario("torque_steps"));
  EXPECT_EQ(*steps[1 + 1000].torque, 0.1 * 2.0);   // t = 1 s: the third of five levels
  EXPECT_EQ(*steps[1 + 1300].torque, 0.1 * -1.0);  // t = 1.3 s: the reversal
  const std::vector<RigEvent> ramp = torqueAndPreload(scenario("preload_ramp"));
  EXPECT_NEAR(ramp[1010].preload.at(0).axial_preload, 200.0 + 1800.0 * 0.5,
              1e-9);  // t = 1 s: 1100 N
}

TEST(RigScenarios, FaultsMoveTheReadingsWithTheLoopedStamps) {
  // From 3/4 of the duration on the whole recording jumps back by 0.6 duration, the encoders too.
  for (const RigEvent& e : joints(scenario("faults"))) {
    ASSERT_EQ(e.stamp_offset, e.t >= 1.5 ? -1.2 : 0.0) << e.t;
    ASSERT_FALSE(e.zero_stamp);
  }
}

TEST(RigScenarios, JointRateAndVelocityOptions) {
  const std::vector<RigEvent> slow = joints(scenario("run_up", 250.0));
  ASSERT_EQ(slow.size(), 500u);
  EXPECT_NEAR(slow[3].t, 0.012, 1e-15);
  EXPECT_TRUE(joints(scenario("run_up", 0.0)).empty());
  for (const RigEvent& e : joints(scenario("reverse", 1000.0, false))) {
    ASSERT_FALSE(e.motion->pinion_velocity);
    ASSERT_FALSE(e.gear_velocity);
    ASSERT_TRUE(e.motion->gear_angle);
  }
}

TEST(RigScenarios, RefusesBadOptionsNamingThem) {
  auto message = [](const ScenarioSpec& spec) {
    try {
      makeScenario(rig(), spec);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  ScenarioSpec spec;
  spec.name = "run_up";
  spec.joint_rate = -1.0;
  EXPECT_EQ(message(spec).rfind("joint_rate = -1", 0), 0u) << message(spec);
  spec.joint_rate = std::nan("");
  EXPECT_EQ(message(spec).rfind("joint_rate = nan", 0), 0u) << message(spec);
  spec.joint_rate = 0.1;  // 0.2 samples in 2 s
  EXPECT_EQ(message(spec).rfind("duration * joint_rate = 0", 0), 0u) << message(spec);
  spec = ScenarioSpec{};
  spec.name = "speed_steps";
  spec.duration = 0.1;
  EXPECT_EQ(message(spec).rfind("duration = 0.1", 0), 0u) << message(spec);
  spec.name = "run_down";
  EXPECT_NE(message(spec).find("unknown"), std::string::npos) << message(spec);
}

// The scenes whose speed changes (run_up, speed_steps, reverse; scenes.hpp): the motion they carry
// is the closed-form speed profile (phase at the readings against kinematics worked out by hand,
// not SpeedProfile), the speed really moves (a wide range, a reversal through zero), and the exact
// propagation at any speed (propagateMotionScene, SlicedModalPropagator) agrees with dopri5 at
// rtol 1e-12 on the same sliced model along the same motion to 1e-8, as drivetrain_bench reports.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {
const RigConfig& rig() { return test::seedServo(); }

constexpr double kT = 0.04;             // [s] 40 readings: T/4 and T/20 fall on readings
constexpr double kRpm = kTwoPi / 60.0;  // 1 rpm in rad/s
constexpr int kPinionTeeth = 20;        // seed 000 Table 1

/// Pinion angle [rad] at t by hand (kinematics of each profile, scenes.hpp), where it is simple.
double handAngle(const std::string& name, double t) {
  if (name == "run_up")
    return 6000.0 * kRpm * t * t / (2.0 * kT);  // uniform acceleration from rest
  if (name == "reverse")
    return 1000.0 * kRpm * kT / kTwoPi *
           std::sin(kTwoPi * t / kT);  // integral of s cos(2 pi t / T)
  // speed_steps, at the end only: dwell at 500 rpm to T/4, then for each step a linear ramp of T/20
  // (the mean of both levels) and the dwell at the new level for the rest of its quarter.
  EXPECT_EQ(t, kT);
  const double level[] = {500.0 * kRpm, 1000.0 * kRpm, 2000.0 * kRpm, 4000.0 * kRpm};
  const double ramp = kT / 20.0;
  double a = level[0] * kT / 4.0;
  for (int i = 1; i < 4; ++i)
    a += 0.5 * (level[i - 1] + level[i]) * ramp + level[i] * (kT / 4.0 - ramp);
  return a;
}

/// Times at which handAngle is checked, per scene.
std::vector<double> checkedTimes(const std::string& name) {
  if (name == "run_up") return {kT / 2.0, kT};
  if (name == "reverse")
    return {kT / 4.0, kT / 2.0, kT};  // furthest forward, back at the start, and again
  return {kT};
}

struct SampledRun {
  std::vector<State6> y;
  std::vector<double> delta;  ///< after the transient
};

SampledRun record(const Scene& s, const std::function<void(const Observer&)>& integrate_with) {
  SampledRun r;
  integrate_with([&](double t, const State6& y) {
    r.y.push_back(y);
    if (t >= s.transient) r.delta.push_back(s.model->forces(t, y).delta);
  });
  return r;
}
}  // namespace

TEST(MotionScenes, PhaseAtTheReadingsIsTheClosedFormIntegralOfTheSpeed) {
  for (const std::string& name : motionSceneNames()) {
    const Scene s = makeScene(name, rig(), kT);
    ASSERT_TRUE(s.motion) << name;
    const SceneMotion& m = *s.motion;
    ASSERT_EQ(m.pinion_teeth, kPinionTeeth);
    ASSERT_EQ(m.readings(), 41u) << name;
    EXPECT_NEAR(s.duration, kT, 1e-15);
    for (double t : checkedTimes(name)) {
      const std::size_t k = static_cast<std::size_t>(std::lround(t / m.reading_interval));
      const double expected =
          m.initial_phase + kPinionTeeth * handAngle(name, t) / kTwoPi;  // [turns]
      EXPECT_NEAR(m.phase[k], expected, 1e-9) << name << " at t = " << t;
      // What the model (dopri5, the peers) sees at that time: the same phase, wrapped.
      MeshInstant mi;
      s.model->excitation().at(t, mi);
      const double wrapped = expected - std::floor(expected);
      EXPECT_NEAR(std::remainder(mi.phase - wrapped, 1.0), 0.0, 1e-9) << name << " at t = " << t;
    }
    // The exact propagator's own phase, advanced reading by reading at the scene's speeds and never
    // re-anchored, ends on the closed form too; and its state is the sampled run's (the step is
    // free).
    const SlicedModalPropagator exact(s.model->parameters(), m.slices, m.te_amplitude, m.backlash);
    State6 y = s.initial;
    double phase = m.phase[0];
    for (std::size_t k = 0; k + 1 < m.readings(); ++k) {
      ASSERT_TRUE(exact.propagate(y, phase, m.meshFrequency(k), m.reading_interval, m.drive_force))
          << name;
    }
    EXPECT_NEAR(phase, m.initial_phase + kPinionTeeth * handAngle(name, kT) / kTwoPi, 1e-9) << name;
    IntegratorOptions fallback;
    const State6 sampled = propagateMotionScene(s, exact, fallback, nullptr);
    EXPECT_LT((sampled - y).head<3>().cwiseAbs().maxCoeff(),
              1e-10 * y.head<3>().cwiseAbs().maxCoeff())
        << name;
  }
}

TEST(MotionScenes, TheSpeedMovesAcrossAWideRangeAndReversesThroughZero) {
  const double mesh_hz_per_rpm = kPinionTeeth / 60.0;
  auto frequencies = [](const Scene& s) {
    std::vector<double> f;
    for (std::size_t k = 0; k + 1 < s.motion->readings(); ++k)
      f.push_back(s.motion->meshFrequency(k));
    return f;
  };
  const std::vector<double> up = frequencies(makeScene("run_up", rig(), kT));
  EXPECT_LT(up.front(), 0.02 * 6000.0 * mesh_hz_per_rpm);  // from rest
  EXPECT_GT(up.back(), 0.97 * 6000.0 * mesh_hz_per_rpm);   // to 6000 rpm
  EXPECT_TRUE(std::is_sorted(up.begin(), up.end()));
  // speed_steps: the middle of each dwell at its level (a reading interval there is all dwell).
  const std::vector<double> steps = frequencies(makeScene("speed_steps", rig(), kT));
  const double levels[] = {500.0, 1000.0, 2000.0, 4000.0};
  for (int i = 0; i < 4; ++i) {
    const std::size_t k =
        static_cast<std::size_t>(10 * i + 6);  // 6-7 ms into a 10 ms quarter (ramp 2 ms)
    EXPECT_NEAR(steps[k], levels[i] * mesh_hz_per_rpm, 1e-9 * levels[i]) << "dwell " << i;
  }
  // reverse: +1000 rpm, through zero to -1000 rpm and back: the sign changes twice.
  const std::vector<double> rev = frequencies(makeScene("reverse", rig(), kT));
  int sign_changes = 0;
  for (std::size_t k = 1; k < rev.size(); ++k) sign_changes += (rev[k] > 0.0) != (rev[k - 1] > 0.0);
  EXPECT_EQ(sign_changes, 2);
  EXPECT_LT(*std::min_element(rev.begin(), rev.end()), -0.99 * 1000.0 * mesh_hz_per_rpm);
  EXPECT_GT(*std::max_element(rev.begin(), rev.end()), 0.99 * 1000.0 * mesh_hz_per_rpm);
}

TEST(MotionScenes, SlicedExactAgreesWithDopri5OnEachScene) {
  for (const std::string& name : motionSceneNames()) {
    const Scene s = makeScene(name, rig(), kT);
    // drivetrain_bench's reference: dopri5 at rtol 1e-12 on the scene's model (the same sliced
    // model along the same readings; slice boundaries and readings are time events).
    IntegratorOptions ref_opt;
    ref_opt.relative_tolerance = 1e-12;
    ref_opt.absolute_tolerance = 1e-18;
    ref_opt.max_step = 1e-4;
    const SampledRun ref = record(s, [&](const Observer& o) {
      integrate(*s.model, IntegratorMethod::kDopri5, ref_opt, 0.0, s.initial, s.duration,
                s.output_interval, o);
    });
    const SlicedModalPropagator exact(s.model->parameters(), s.motion->slices,
                                      s.motion->te_amplitude, s.motion->backlash);
    IntegratorOptions fallback = ref_opt;
    fallback.relative_tolerance = 1e-9;
    IntegrationStats stats;
    const SampledRun got =
        record(s, [&](const Observer& o) { propagateMotionScene(s, exact, fallback, o, &stats); });
    ASSERT_EQ(got.y.size(), ref.y.size()) << name;
    ASSERT_EQ(got.delta.size(), ref.delta.size()) << name;
    EXPECT_EQ(stats.fallbacks, 0) << name << ": the contacts stay closed at 0.1 N m";
    EXPECT_GT(stats.steps, 0) << name;
    double e = 0.0, r = 0.0, dmax = 0.0, ymax = 0.0;
    for (std::size_t i = 0; i < got.delta.size(); ++i) {
      e += (got.delta[i] - ref.delta[i]) * (got.delta[i] - ref.delta[i]);
      r += ref.delta[i] * ref.delta[i];
    }
    for (std::size_t i = 0; i < got.y.size(); ++i) {
      dmax = std::max(dmax, (got.y[i] - ref.y[i]).head<3>().cwiseAbs().maxCoeff());
      ymax = std::max(ymax, ref.y[i].head<3>().cwiseAbs().maxCoeff());
    }
    EXPECT_LT(std::sqrt(e / r), 1e-8) << name << ": err_rms_rel of the mesh deflection";
    EXPECT_LT(dmax / ymax, 1e-8) << name
                                 << ": largest displacement error over the largest displacement";
  }
}

TEST(MotionScenes, DurationOnlyForTheMotionScenes) {
  EXPECT_THROW(makeScene("nominal", rig(), 0.5), InvalidInput);
  EXPECT_THROW(makeScene("run_up", rig(), 0.01), InvalidInput);  // fewer than 20 readings
  EXPECT_EQ(makeScene("run_up", rig()).duration, 1.0);
  EXPECT_THROW(propagateMotionScene(
                   makeScene("nominal", rig()),
                   SlicedModalPropagator(makeScene("run_up", rig(), kT).model->parameters(),
                                         makeScene("run_up", rig(), kT).motion->slices, 1e-6, 0.0),
                   IntegratorOptions{}, nullptr),
               InvalidInput);
}

// The hard scenes: every method either stays bounded and finite at its configured step or refuses
// with a clear error, the methods agree where the motion is regular, and each scene shows the
// physics it is named for.
#include <gtest/gtest.h>

#include <algorithm>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {
const RigConfig& rig() { return test::seedServo(); }

IntegratorOptions optionsFor(const Scene& s, IntegratorMethod m) {
  IntegratorOptions o;
  o.step = s.suggested_step;
  o.max_step = s.units == "SI" ? 1e-4 : 0.1;
  o.relative_tolerance = 1e-9;
  o.absolute_tolerance = s.units == "SI" ? 1e-15 : 1e-11;
  if (s.units != "SI") o.divergence_limit = 1e3;
  (void)m;
  return o;
}

struct SceneRun {
  double peak_delta = 0.0;
  int drive_opened = 0, back_opened = 0, back_reclosed = 0, bearing_changes = 0;
  bool finite = true;
};

SceneRun run(const Scene& s, IntegratorMethod m) {
  SceneRun r;
  ContactRegime last;
  bool first = true;
  integrate(*s.model, m, optionsFor(s, m), 0.0, s.initial, s.duration, s.output_interval,
            [&](double t, const State6& y) {
              r.finite &= y.allFinite();
              const GearRotorForces f = s.model->forces(t, y);
              if (t >= s.transient) r.peak_delta = std::max(r.peak_delta, std::abs(f.delta));
              if (!first) {
                r.drive_opened += last.code[0] == 1 && f.regime.code[0] == 0;
                r.back_opened += last.code[1] == 1 && f.regime.code[1] == 0;
                r.back_reclosed += last.code[1] == 0 && f.regime.code[1] == 1;
                r.bearing_changes += last.code[2] != f.regime.code[2];
              }
              last = f.regime;
              first = false;
            });
  return r;
}
}  // namespace

TEST(Scenes, EveryMethodBoundedOrRefusesOnEveryScene) {
  const std::vector<std::string> moving = motionSceneNames();
  for (const std::string& name : sceneNames()) {
    // The scenes whose speed changes at 50 ms instead of their default 1 s (test time).
    const bool motion = std::find(moving.begin(), moving.end(), name) != moving.end();
    const Scene s = makeScene(name, rig(), motion ? 0.05 : 0.0);
    double reference = 0.0;
    for (auto m :
         {IntegratorMethod::kDopri5, IntegratorMethod::kRk4, IntegratorMethod::kTrapezoidal}) {
      try {
        const SceneRun r = run(s, m);
        EXPECT_TRUE(r.finite) << name << " " << toString(m);
        EXPECT_GT(r.peak_delta, 0.0) << name;
        if (m == IntegratorMethod::kDopri5) {
          reference = r.peak_delta;
        } else if (name != "chaotic" && name != "bearing_rattle") {
          // Regular motion: the methods agree. Not compared: chaotic, and bearing_rattle, whose
          // impacts (about 170 in 20 ms) make the trajectory sensitive to any perturbation - two
          // dopri5 references at rtol 1e-9 and 1e-12 differ by 10 % (drivetrain_bench).
          EXPECT_NEAR(r.peak_delta / reference, 1.0, 0.02) << name << " " << toString(m);
        }
      } catch (const UnstableIntegration& e) {
        ADD_FAILURE() << name << " " << toString(m)
                      << " refused at its own suggested step: " << e.what();
      }
    }
  }
}

TEST(Scenes, EachSceneShowsItsPhysics) {
  // low_preload: the g2 flank separates and re-impacts.
  const SceneRun low = run(makeScene("low_preload", rig()), IntegratorMethod::kDopri5);
  EXPECT_GT(low.back_opened, 0);
  EXPECT_GT(low.back_reclosed, 0);
  // torque_steps: the reversal to -0.3 N m stays inside the anti-backlash window: no flank opens.
  const SceneRun steps = run(makeScene("torque_steps", rig()), IntegratorMethod::kDopri5);
  EXPECT_EQ(steps.drive_opened, 0);
  EXPECT_EQ(steps.back_opened, 0);
  // bearing_rattle: the shafts cross their clearance back and forth.
  EXPECT_GT(run(makeScene("bearing_rattle", rig()), IntegratorMethod::kDopri5).bearing_changes, 4);
  // kahraman_singh / chaotic: contact is lost (the dead zone is entered) in steady state.
  EXPECT_GT(run(makeScene("kahraman_singh", rig()), IntegratorMethod::kDopri5).drive_opened, 0);
  EXPECT_GT(run(makeScene("chaotic", rig()), IntegratorMethod::kDopri5).drive_opened, 0);
}

TEST(Scenes, ExplicitMethodRefusesBeyondItsLimitOnNearRigidBearings) {
  const Scene s = makeScene("near_rigid_bearings", rig());
  IntegratorOptions o = optionsFor(s, IntegratorMethod::kRk4);
  o.step = 1e-5;  // 200x the suggested step: far beyond 2.79 / omega_max
  EXPECT_THROW(integrate(*s.model, IntegratorMethod::kRk4, o, 0.0, s.initial, 1e-3, 1e-5, nullptr),
               UnstableIntegration);
  const State6 y =
      integrate(*s.model, IntegratorMethod::kTrapezoidal, o, 0.0, s.initial, 1e-3, 1e-5, nullptr);
  EXPECT_TRUE(y.allFinite());
}

TEST(Scenes, UnknownSceneAndMissingDynamicsAreClearErrors) {
  EXPECT_THROW(makeScene("typhoon", rig()), InvalidInput);
  RigConfig no_dynamics = rig();
  no_dynamics.dynamics.present = false;
  EXPECT_THROW(makeScene("nominal", no_dynamics), InvalidInput);
}

// Exact-exponential propagation: on the nominal scene (contacts closed) it matches the dopri5
// reference; where a flank opens it hands over to dopri5 and still matches; with bearing clearance
// it refuses; an output interval that does not divide the mesh period is refused.
TEST(Scenes, ExponentialMethod) {
  const Scene s = makeScene("nominal", rig());
  IntegratorOptions ref = optionsFor(s, IntegratorMethod::kDopri5);
  ref.relative_tolerance = 1e-12;
  ref.absolute_tolerance = 1e-18;
  auto deltas = [&](const Scene& scene, IntegratorMethod m, const IntegratorOptions& o,
                    IntegrationStats* st) {
    std::vector<double> d;
    integrate(
        *scene.model, m, o, 0.0, scene.initial, scene.duration, scene.output_interval,
        [&](double t, const State6& y) { d.push_back(scene.model->forces(t, y).delta); }, st);
    return d;
  };
  auto relErr = [](const std::vector<double>& a, const std::vector<double>& b) {
    double e = 0, r = 0;
    for (std::size_t i = 0; i < b.size(); ++i) {
      e += (a[i] - b[i]) * (a[i] - b[i]);
      r += b[i] * b[i];
    }
    return std::sqrt(e / r);
  };
  const std::vector<double> reference = deltas(s, IntegratorMethod::kDopri5, ref, nullptr);
  IntegrationStats st;
  const std::vector<double> exact =
      deltas(s, IntegratorMethod::kExponential, IntegratorOptions{}, &st);
  ASSERT_EQ(exact.size(), reference.size());
  EXPECT_LT(relErr(exact, reference), 1e-7);
  EXPECT_EQ(st.fallbacks, 0);

  const Scene low = makeScene("low_preload", rig());
  const std::vector<double> low_ref = deltas(low, IntegratorMethod::kDopri5, ref, nullptr);
  IntegratorOptions handover = ref;
  handover.relative_tolerance = 1e-10;
  handover.absolute_tolerance = 1e-16;
  const std::vector<double> low_exp = deltas(low, IntegratorMethod::kExponential, handover, &st);
  ASSERT_EQ(low_exp.size(), low_ref.size());
  EXPECT_EQ(st.fallbacks, 1);  // the g2 flank opens: dopri5 takes over
  EXPECT_LT(relErr(low_exp, low_ref), 1e-5);

  // Torque steps at 5, 10 and 15 ms, each inside an output interval (5 ms is 53.3 intervals of
  // 93.75 us): carried exactly by the unit-step responses at their instants, with no dopri5 (no
  // right-hand side evaluated) and no smearing. The reference is dopri5 at rtol 1e-12 landing on
  // each step.
  const Scene steps = makeScene("torque_steps", rig());
  const std::vector<double> steps_ref = deltas(steps, IntegratorMethod::kDopri5, ref, nullptr);
  const std::vector<double> steps_exp =
      deltas(steps, IntegratorMethod::kExponential, handover, &st);
  ASSERT_EQ(steps_exp.size(), steps_ref.size());
  EXPECT_EQ(st.fallbacks, 0);
  EXPECT_EQ(st.events, 3);
  EXPECT_EQ(st.rhs_evaluations, 0);
  EXPECT_LT(relErr(steps_exp, steps_ref), 1e-7);

  const Scene rattle = makeScene("bearing_rattle", rig());
  EXPECT_THROW(integrate(*rattle.model, IntegratorMethod::kExponential, IntegratorOptions{}, 0.0,
                         rattle.initial, rattle.duration, rattle.output_interval, nullptr),
               InvalidInput);
  EXPECT_THROW(integrate(*s.model, IntegratorMethod::kExponential, IntegratorOptions{}, 0.0,
                         s.initial, s.duration, s.output_interval * 1.37, nullptr),
               InvalidInput);
}

// Every output sample is delivered through crowded events. Regression: on low_preload a step shrunk
// to nothing by an event right at its start once ended the dopri5 run early, silently dropping the
// remaining samples (129 of 225 delivered).
TEST(Scenes, Dopri5DeliversEverySampleThroughFlankImpacts) {
  const Scene s = makeScene("low_preload", rig());
  IntegratorOptions o = optionsFor(s, IntegratorMethod::kDopri5);
  o.relative_tolerance = 1e-12;
  o.absolute_tolerance = 1e-18;
  long samples = 0;
  double last = -1.0;
  integrate(*s.model, IntegratorMethod::kDopri5, o, 0.0, s.initial, s.duration, s.output_interval,
            [&](double t, const State6&) {
              ++samples;
              last = t;
            });
  EXPECT_EQ(samples, std::lround(s.duration / s.output_interval) + 1);
  EXPECT_NEAR(last, s.duration, 1e-9 * s.duration);
}

// The backlash oscillator's softening resonance jumps: sweeping up, the response stays on the
// small no-impact branch and jumps up to the impacting branch; sweeping down from above, it stays
// on the impacting branch well below that frequency (hysteresis). Away from the window both
// sweeps agree.
TEST(Scenes, KahramanSinghSweepShowsJumpHysteresis) {
  std::vector<double> up;
  for (int i = 0; i <= 14; ++i) up.push_back(0.5 + 0.05 * i);
  const std::vector<double> down(up.rbegin(), up.rend());
  const OscillatorSweepSpec spec;
  const std::vector<SweepPoint> u = sweepOscillator(spec, up), d = sweepOscillator(spec, down);
  auto at = [](const std::vector<SweepPoint>& v, double w) {
    for (const SweepPoint& p : v)
      if (std::abs(p.frequency - w) < 1e-9) return p;
    return SweepPoint{};
  };
  const SweepPoint up06 = at(u, 0.6), down06 = at(d, 0.6);
  EXPECT_EQ(up06.regime, "no_impact");
  EXPECT_NE(down06.regime, "no_impact");
  EXPECT_GT(down06.peak_to_peak, 3.0 * up06.peak_to_peak);
  EXPECT_NEAR(at(u, 1.1).peak_to_peak / at(d, 1.1).peak_to_peak, 1.0, 0.01);
  // The up-sweep jumps somewhere in the window: a rise of at least 2x between neighbours.
  bool jump = false;
  for (std::size_t i = 1; i < u.size(); ++i)
    jump |= u[i].peak_to_peak > 2.0 * u[i - 1].peak_to_peak;
  EXPECT_TRUE(jump);
}

// The chaotic scene earns its name: a 1e-9 perturbation of the initial state grows to O(1)
// (positive largest Lyapunov exponent, estimated from the growth rate), while the same perturbation
// of the periodic kahraman_singh scene stays at its initial size.
TEST(Scenes, ChaoticSceneHasSensitiveDependence) {
  auto separation = [](const Scene& s, double* growth_time) {
    IntegratorOptions o;
    o.relative_tolerance = 1e-11;
    o.absolute_tolerance = 1e-13;
    o.max_step = 0.1;
    o.divergence_limit = 1e3;
    State6 b = s.initial;
    b[2] += 1e-9;
    std::vector<double> xa, xb, t;
    integrate(*s.model, IntegratorMethod::kDopri5, o, 0.0, s.initial, s.duration,
              s.output_interval * 10, [&](double tt, const State6& y) {
                xa.push_back(y[2]);
                t.push_back(tt);
              });
    integrate(*s.model, IntegratorMethod::kDopri5, o, 0.0, b, s.duration, s.output_interval * 10,
              [&](double, const State6& y) { xb.push_back(y[2]); });
    double worst = 0.0;
    *growth_time = INFINITY;
    for (std::size_t i = 0; i < xa.size(); ++i) {
      worst = std::max(worst, std::abs(xa[i] - xb[i]));
      if (*growth_time == INFINITY && std::abs(xa[i] - xb[i]) > 1e-4) *growth_time = t[i];
    }
    return worst;
  };
  double t_chaotic = 0.0, t_regular = 0.0;
  EXPECT_GT(separation(makeScene("chaotic", rig()), &t_chaotic), 1e-2);
  EXPECT_LT(separation(makeScene("kahraman_singh", rig()), &t_regular), 1e-6);
  // Growth by 1e5 in t_chaotic: lambda = ln(1e5) / t > 0 (about 0.07 per unit time here).
  EXPECT_GT(std::log(1e5) / t_chaotic, 0.01);
}

// At rtol 1e-12 / atol 1e-19 a tooth switch 1e-12 turn ahead is hit exactly: a step that skipped
// it would straddle it at the smallest step size and be rejected forever.
TEST(Scenes, Dopri5TightTolerancesFinish) {
  const Scene s = makeScene("nominal", rig());
  IntegratorOptions o;
  o.relative_tolerance = 1e-12;
  o.absolute_tolerance = 1e-19;
  o.max_step = 1e-4;
  long samples = 0;
  try {
    integrate(*s.model, IntegratorMethod::kDopri5, o, 0.0, s.initial, s.duration, s.output_interval,
              [&](double, const State6&) { ++samples; });
    EXPECT_EQ(samples, std::lround(s.duration / s.output_interval) + 1);
  } catch (const UnstableIntegration& e) {
    // Acceptable: a clear refusal (step-size underflow), never a hang.
    EXPECT_NE(std::string(e.what()).find("underflow"), std::string::npos) << e.what();
  }
}

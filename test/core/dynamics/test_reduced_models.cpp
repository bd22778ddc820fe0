// Reduced fidelities and the automatic choice, against the limits they stand for.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <complex>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {
const RigConfig& rig() { return test::seedServo(); }

std::vector<double> deltas(const GearRotorModel& m, const Scene& s,
                           const std::function<void(const Observer&)>& run) {
  std::vector<double> d;
  run([&](double t, const State6& y) {
    if (t >= s.transient) d.push_back(m.forces(t, y).delta);
  });
  return d;
}

double relErr(const std::vector<double>& a, const std::vector<double>& b) {
  double e = 0, r = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    e += (a[i] - b[i]) * (a[i] - b[i]);
    r += b[i] * b[i];
  }
  return std::sqrt(e / r);
}

// The nominal scene's model with the gear inertias scaled (a lighter torsional mode).
std::shared_ptr<GearRotorModel> withInertiaScale(const Scene& s, double scale) {
  GearRotorParameters p = s.model->parameters();
  p.pinion_inertia *= scale;
  p.gear_inertia *= scale;
  const RigExcitation& e = *s.model->rigExcitation();
  auto mesh = std::shared_ptr<const AntiBacklashMesh>(&e.mesh(), [](const AntiBacklashMesh*) {});
  return std::make_shared<GearRotorModel>(p, std::make_shared<RigExcitation>(mesh, p, e.spec()));
}
}  // namespace

// Quasi-static torsion is the m_s -> 0 limit: its error against the full model falls as the
// torsional mode stiffens (inertias scaled by 1e-2 raise it tenfold).
TEST(ReducedModels, QuasiStaticIsTheLightTorsionLimit) {
  const Scene s = makeScene("nominal", rig());
  IntegratorOptions o;
  o.relative_tolerance = 1e-10;
  o.absolute_tolerance = 1e-16;
  auto errorFor = [&](double scale) {
    const auto model = withInertiaScale(s, scale);
    const State6 y0 = staticEquilibrium(*model, 0.0);
    const auto full = deltas(*model, s, [&](const Observer& ob) {
      integrate(*model, IntegratorMethod::kExponential, o, 0.0, y0, s.duration, s.output_interval,
                ob);
    });
    const auto qs = deltas(*model, s, [&](const Observer& ob) {
      integrateReduced(*model, Fidelity::kQuasiStatic, 0.0, y0, s.duration, s.output_interval, ob);
    });
    return relErr(qs, full);
  };
  const double coarse = errorFor(1.0), fine = errorFor(1e-2);
  EXPECT_LT(coarse, 0.2);
  EXPECT_LT(fine, 0.5 * coarse);
}

// Linear modal (mean stiffness, LTI): its steady-state response to the TE at the mesh frequency
// equals the analytic frequency response q = (K - w^2 M + i w C)^-1 f of docs/model.md's matrices,
// with the TE entering the mesh force as -(k_s + i w c_s) A on (x_p, x_g, x) with signs (-1, +1,
// -1).
TEST(ReducedModels, LinearModalMatchesAnalyticFrequencyResponse) {
  const Scene s = makeScene("nominal", rig());
  const RigExcitation& e = *s.model->rigExcitation();
  const GearRotorParameters& p = s.model->parameters();
  // The model's mean stiffness: the phase table's exact period mean of k_drive + k_back = k1 + k_c
  // (checked against two independent quadratures in test_mesh_stiffness.cpp,
  // AntiBacklashMesh.PeriodMeansAreTheExactIntegralsOfThePhaseTable).
  const double ks = e.mesh().periodMeans().k1 + e.mesh().periodMeans().k_chain;
  const double w = 2 * M_PI * e.meshFrequency(), a = e.spec().te_amplitude, cs = p.mesh_damping,
               ms = s.model->equivalentMass();
  using C = std::complex<double>;
  Eigen::Matrix3cd d;
  const C kc(ks, w * cs);
  d << C(p.bearing_stiffness[0] - w * w * p.pinion_mass, w * p.bearing_damping[0]) + kc, -kc, kc,
      -kc, C(p.bearing_stiffness[1] - w * w * p.gear_mass, w * p.bearing_damping[1]) + kc, -kc, kc,
      -kc, -w * w * ms + kc;
  const Eigen::Vector3cd f =
      kc * a * Eigen::Vector3cd(1.0, -1.0, 1.0);  // e(t) = A sin(w t) = Im(A e^{iwt})
  const Eigen::Vector3cd q = d.partialPivLu().solve(f);
  const C delta_amp = q[2] + q[0] - q[1] - a;  // delta = x + x_p - x_g - e
  // Simulate long enough for the transient to decay and fit A sin + B cos + mean over the last
  // periods.
  const double period = 1.0 / e.meshFrequency();
  std::vector<std::pair<double, double>> samples;
  integrateReduced(*s.model, Fidelity::kLinearModal, 0.0, s.initial, 200 * period,
                   s.output_interval, [&](double t, const State6& y) {
                     if (t > 190 * period) samples.emplace_back(t, s.model->forces(t, y).delta);
                   });
  Eigen::MatrixXd basis(samples.size(), 3);
  Eigen::VectorXd values(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    basis(i, 0) = std::sin(w * samples[i].first);
    basis(i, 1) = std::cos(w * samples[i].first);
    basis(i, 2) = 1.0;
    values[i] = samples[i].second;
  }
  const Eigen::Vector3d fit = basis.colPivHouseholderQr().solve(values);
  EXPECT_NEAR(std::hypot(fit[0], fit[1]) / std::abs(delta_amp), 1.0, 1e-6);
  MeshInstant m0;
  e.at(0.0, m0);
  EXPECT_NEAR(fit[2] / (m0.drive_force / ks), 1.0, 1e-6);  // mean deflection F_m / k_mean
}

TEST(ReducedModels, AutomaticChoiceIsTheCheapestThatMeetsTheBound) {
  const Scene s = makeScene("nominal", rig());
  const double pilot = 4.0 / (1000.0 / 60 * 20);
  EXPECT_EQ(chooseAutomatically(*s.model, 0.0, s.initial, s.output_interval, pilot, 0.5).fidelity,
            Fidelity::kQuasiStatic);
  const AutoChoice tight =
      chooseAutomatically(*s.model, 0.0, s.initial, s.output_interval, pilot, 1e-6);
  EXPECT_EQ(tight.fidelity, Fidelity::kFull);
  EXPECT_EQ(tight.method, IntegratorMethod::kExponential);
  EXPECT_FALSE(tight.reason.empty());
  const Scene rattle = makeScene("bearing_rattle", rig());
  const AutoChoice r =
      chooseAutomatically(*rattle.model, 0.0, rattle.initial, rattle.output_interval, pilot, 1e-3);
  EXPECT_EQ(r.method, IntegratorMethod::kDopri5);  // clearance: no exact propagation
  EXPECT_NEAR(r.relative_tolerance, 1e-5, 1e-18);
}

// auto weighs the exponential method's set-up (one 11x11 exponential per 1/omega_max over a mesh
// period) against dopri5's work over the run, from counts, not clocks: on the stiff
// near_rigid_bearings scene (bearings 100x stiffer: omega_max about 10x the nominal one, so about
// 10x the Magnus steps) a 3 ms run is cheaper with dopri5, a long one with the exponential method.
// Whatever it picks must meet its bound against an independent dopri5 at rtol 1e-12 over the
// run (after the scene's start transient, as the bench's err_rms_rel), and a chosen exponential
// method must give exactly what a fresh one gives (its propagators are the pilot's, built once).
TEST(ReducedModels, AutoWeighsTheSetUpAgainstTheRunAndMeetsItsBound) {
  for (const char* name : {"nominal", "near_rigid_bearings", "low_preload"}) {
    const Scene s = makeScene(name, rig());
    const double pilot = defaultPilotDuration(s.duration, s.output_interval), bound = 1e-6;
    const AutoChoice c =
        chooseAutomatically(*s.model, 0.0, s.initial, s.output_interval, pilot, bound, s.duration);
    // The error as the bench measures it (err_rms_rel: delta after the scene's start transient).
    std::vector<double> chosen, reference;
    integrateChoice(*s.model, c, 0.0, s.initial, s.duration, s.output_interval,
                    [&](double t, const State6& y) {
                      if (t >= s.transient) chosen.push_back(s.model->forces(t, y).delta);
                    });
    IntegratorOptions tight;
    tight.relative_tolerance = 1e-12;
    tight.absolute_tolerance = 1e-18;
    tight.max_step = 1e-4;
    integrate(*s.model, IntegratorMethod::kDopri5, tight, 0.0, s.initial, s.duration,
              s.output_interval, [&](double t, const State6& y) {
                if (t >= s.transient) reference.push_back(s.model->forces(t, y).delta);
              });
    ASSERT_EQ(chosen.size(), reference.size()) << name;
    double e = 0.0, r = 0.0;
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      e += (chosen[i] - reference[i]) * (chosen[i] - reference[i]);
      r += reference[i] * reference[i];
    }
    EXPECT_LE(std::sqrt(e / r), bound) << name << ": " << c.reason;
    if (c.method == IntegratorMethod::kExponential) {
      ASSERT_TRUE(c.exponential) << name;
      std::vector<double> fresh;
      integrate(*s.model, IntegratorMethod::kExponential, IntegratorOptions{}, 0.0, s.initial,
                s.duration, s.output_interval, [&](double t, const State6& y) {
                  if (t >= s.transient) fresh.push_back(s.model->forces(t, y).delta);
                });
      EXPECT_EQ(fresh, chosen) << name;
    }
  }
  // dopri5 counts its steps over the pilot's first kDopriCountSamples samples and runs the whole
  // pilot only where it is still needed: not on nominal, where the exponential method is chosen
  // and is the reference; on low_preload, where a contact opens in the exponential method's pilot,
  // it is the reference again, over the whole pilot from the start; at a bound below
  // kExponentialReferenceBound, where the exponential method cannot be the reference, the whole
  // pilot at once, no count before it (counts, not clocks).
  struct Case {
    const char* scene;
    double bound;
    bool count, whole;
  };
  for (const Case& k : {Case{"nominal", 1e-6, true, false}, Case{"low_preload", 1e-6, true, true},
                        Case{"nominal", 1e-7, false, true}}) {
    const Scene s = makeScene(k.scene, rig());
    const double pilot = defaultPilotDuration(s.duration, s.output_interval);
    const AutoChoice c = chooseAutomatically(*s.model, 0.0, s.initial, s.output_interval, pilot,
                                             k.bound, s.duration);
    const IntegratorOptions dopri = autoOptions(IntegratorMethod::kDopri5, c.relative_tolerance);
    IntegrationStats count, whole;
    integrate(*s.model, IntegratorMethod::kDopri5, dopri, 0.0, s.initial,
              kDopriCountSamples * s.output_interval, s.output_interval, nullptr, &count);
    integrate(*s.model, IntegratorMethod::kDopri5, dopri, 0.0, s.initial, c.pilot_duration,
              s.output_interval, nullptr, &whole);
    ASSERT_LT(count.steps, whole.steps) << k.scene;
    EXPECT_EQ(c.dopri_pilot_steps, (k.count ? count.steps : 0) + (k.whole ? whole.steps : 0))
        << k.scene << " at " << k.bound << ": " << c.reason;
  }
  const Scene stiff = makeScene("near_rigid_bearings", rig());
  const double pilot = 10 * stiff.output_interval;
  const AutoChoice short_run = chooseAutomatically(*stiff.model, 0.0, stiff.initial,
                                                   stiff.output_interval, pilot, 1e-6, 3e-3);
  EXPECT_EQ(short_run.method, IntegratorMethod::kDopri5) << short_run.reason;
  EXPECT_FALSE(short_run.exponential);
  const AutoChoice long_run = chooseAutomatically(*stiff.model, 0.0, stiff.initial,
                                                  stiff.output_interval, pilot, 1e-6, 10.0);
  EXPECT_EQ(long_run.method, IntegratorMethod::kExponential) << long_run.reason;
}

// Review findings: the backlash offset of an ordinary gear in both reduced models (and its sign
// under a reversed load), and a pilot too short to compare anything.
TEST(ReducedModels, OrdinaryGearBacklashOffset) {
  const RigConfig ordinary =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/test/data/ordinary_servo.yaml");
  for (double torque : {0.1, -0.1}) {
    RigConfig r = ordinary;
    r.dynamics.torque = torque;
    const Scene s = makeScene("nominal", r);
    const RigExcitation& e = *s.model->rigExcitation();
    MeshInstant m;
    e.at(0.0, m);
    const double b = std::copysign(5e-6, m.drive_force);
    for (Fidelity f : {Fidelity::kQuasiStatic, Fidelity::kLinearModal}) {
      double mean = 0.0;
      long n = 0;
      integrateReduced(*s.model, f, 0.0, s.initial, s.duration, s.output_interval,
                       [&](double t, const State6& y) {
                         if (t >= s.transient) {
                           mean += s.model->forces(t, y).delta;
                           ++n;
                         }
                       });
      mean /= n;
      // Mean deflection: the backlash plus the elastic part (k_s between single and double pair).
      EXPECT_GT(mean * b, 0.0) << toString(f) << " torque " << torque;
      EXPECT_NEAR(mean - b, m.drive_force / 1.2e8, 0.5 * std::abs(m.drive_force / 1.2e8))
          << toString(f) << " " << torque;
    }
  }
}

TEST(ReducedModels, ShortPilotStillCompares) {
  const Scene s = makeScene("nominal", rig());
  const AutoChoice c = chooseAutomatically(*s.model, 0.0, s.initial, s.output_interval,
                                           0.3 * s.output_interval, 1e-9);
  EXPECT_NE(c.fidelity, Fidelity::kQuasiStatic);  // once chosen on the start state alone
  EXPECT_GE(c.pilot_duration, 4 * s.output_interval * (1 - 1e-12));
}

// The names the CLI accepts are the names toString prints, and a wrong one is named in the error.
TEST(ReducedModels, ParseFidelityRoundTripsAndNamesTheField) {
  for (Fidelity f : {Fidelity::kFull, Fidelity::kQuasiStatic, Fidelity::kLinearModal})
    EXPECT_EQ(parseFidelity("--fidelity", toString(f)), f);
  try {
    parseFidelity("--fidelity", "modal");
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("--fidelity = 'modal'"), std::string::npos) << e.what();
  }
}

// auto on the dimensionless oscillators (gear.md section 3) runs in their units: a state of O(1)
// (the unit gap) is 100x past the SI divergence limit (0.01 m) and a step of 1e-4 would take 25
// million steps over kahraman_singh's 2513 time units, so with SI options dopri5 "diverged" at
// its first step (drivetrain_bench's auto rows of 2026-11-26 for kahraman_singh and chaotic).
// With the scene's scale it meets its bound against dopri5 at rtol 1e-12 in the same units, as the
// bench measures it (delta after the transient), and it refuses nothing.
TEST(ReducedModels, AutoOnTheDimensionlessOscillatorRunsInItsUnits) {
  const Scene s = makeScene("kahraman_singh", rig());
  ASSERT_EQ(s.units, "dimensionless");
  const double pilot = defaultPilotDuration(s.duration, s.output_interval), bound = 1e-6;
  EXPECT_THROW(
      {
        const AutoChoice si = chooseAutomatically(*s.model, 0.0, s.initial, s.output_interval,
                                                  pilot, bound, s.duration);
        integrateChoice(*s.model, si, 0.0, s.initial, s.duration, s.output_interval, nullptr);
      },
      UnstableIntegration)
      << "the SI defaults should not fit this scene (else this test shows nothing)";
  const AutoChoice c = chooseAutomatically(*s.model, 0.0, s.initial, s.output_interval, pilot,
                                           bound, s.duration, s.scale());
  EXPECT_EQ(c.fidelity, Fidelity::kFull);
  EXPECT_EQ(c.method, IntegratorMethod::kDopri5)
      << "no rig excitation: neither reduced nor exponential applies";
  EXPECT_EQ(c.scale.divergence_limit, IntegratorScale::dimensionless().divergence_limit);
  const std::vector<double> chosen = deltas(*s.model, s, [&](const Observer& o) {
    integrateChoice(*s.model, c, 0.0, s.initial, s.duration, s.output_interval, o);
  });
  IntegratorOptions tight;
  tight.relative_tolerance = 1e-12;
  tight.absolute_tolerance = 1e-12 * s.scale().displacement;
  tight.max_step = s.scale().max_step;
  tight.divergence_limit = s.scale().divergence_limit;
  const std::vector<double> reference = deltas(*s.model, s, [&](const Observer& o) {
    integrate(*s.model, IntegratorMethod::kDopri5, tight, 0.0, s.initial, s.duration,
              s.output_interval, o);
  });
  ASSERT_EQ(chosen.size(), reference.size());
  ASSERT_GT(reference.size(), 100u);
  EXPECT_LE(relErr(chosen, reference), bound) << c.reason;
}

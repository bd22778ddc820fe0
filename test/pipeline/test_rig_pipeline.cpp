// The online pipeline shared by the node, the nodelet and drivetrain_replay: its documented time
// rules (zero stamps, out-of-order stamps, bursts, gaps, clock and stamp jumps back), value rules
// (nothing non-finite reaches a sink, the state is never poisoned), determinism, and the two
// shortcuts it takes for speed, each checked against the exact computation it replaces.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <tuple>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() { return test::seedServo(); }

constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;  // 2026-01-01: a wall-clock epoch
Stamp at(double seconds) { return Stamp{kEpoch + std::llround(seconds * 1e9)}; }

// Records everything, and fails the test on any non-finite number.
struct Recorder : PipelineSink {
  std::vector<std::pair<Stamp, StiffnessEstimate>> stiffness_out;
  std::vector<DynamicsSample> te;
  std::vector<Stamp> te_stamps;
  std::vector<std::pair<Stamp, ResonanceEstimate>> resonance_out;
  int spectra = 0;
  void stiffness(Stamp s, const StiffnessEstimate& e, const CalibrationBands&) override {
    for (const SupportEstimate& b : e.supports)
      EXPECT_TRUE(std::isfinite(b.solution.radialStiffness()));
    EXPECT_TRUE(std::isfinite(e.mesh.current.composite));
    stiffness_out.emplace_back(s, e);
  }
  void transmissionError(Stamp stamp, const DynamicsSample& s, const SampleContext&) override {
    EXPECT_EQ(s.t, stamp.toSec());
    te_stamps.push_back(stamp);
    EXPECT_TRUE(s.state.allFinite() && std::isfinite(s.dynamic_te) && std::isfinite(s.mesh_force));
    te.push_back(s);
  }
  void spectrum(Stamp, const SpectrumPeaks&) override { ++spectra; }
  void resonance(Stamp s, const ResonanceEstimate& r, const CalibrationBands&) override {
    for (const Mode& m : r.modes)
      EXPECT_TRUE(std::isfinite(m.natural_frequency) && std::isfinite(m.damping_ratio));
    resonance_out.emplace_back(s, r);
  }
};

std::vector<PreloadSetting> preloads(double axial) {
  return {{"pinion_bearing", axial, 1000.0, 0.0, 0.0}, {"gear_bearing", axial, 1000.0, 0.0, 0.0}};
}

}  // namespace

TEST(RigPipeline, OptionsAreValidatedWithTheFieldNamed) {
  PipelineOptions o;
  o.output_rate = -1.0;
  try {
    RigPipeline p(rig(), o);
    FAIL() << "accepted a negative output_rate";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("output_rate"), std::string::npos) << e.what();
  }
  o = PipelineOptions{};
  o.spectrum_hop = 0;
  EXPECT_THROW(RigPipeline(rig(), o), InvalidInput);
  o = PipelineOptions{};
  o.resonance_threshold = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(RigPipeline(rig(), o), InvalidInput);
  o = PipelineOptions{};
  o.limits.load_tolerance = 0.5;
  EXPECT_THROW(RigPipeline(rig(), o), InvalidInput);
}

// The zero-stamp and value rules: a zero stamp, NaN, Inf and absurd torques, a negative preload and
// an unknown bearing are rejected and counted by reason; the next good input is answered exactly as
// if they had never come (the state is not poisoned).
TEST(RigPipeline, BadInputsAreCountedAndDoNotPoisonTheState) {
  RigPipeline clean(rig(), PipelineOptions{}), dirty(rig(), PipelineOptions{});
  Recorder a, b;
  ASSERT_EQ(clean.torque(at(0.0), 0.1, a), InputOutcome::kAccepted);
  ASSERT_EQ(dirty.torque(at(0.0), 0.1, b), InputOutcome::kAccepted);
  EXPECT_EQ(dirty.torque(Stamp{0}, 0.1, b), InputOutcome::kZeroStamp);
  EXPECT_EQ(dirty.torque(at(0.01), std::numeric_limits<double>::quiet_NaN(), b),
            InputOutcome::kInvalidValue);
  EXPECT_EQ(dirty.torque(at(0.02), std::numeric_limits<double>::infinity(), b),
            InputOutcome::kInvalidValue);
  EXPECT_EQ(dirty.torque(at(0.03), 1e9, b), InputOutcome::kInvalidValue);
  EXPECT_EQ(dirty.preload(at(0.04), preloads(-5.0), b), InputOutcome::kInvalidValue);
  EXPECT_EQ(dirty.preload(at(0.05), {{"no_such_bearing", 100.0, 0.0, 0.0, 0.0}}, b),
            InputOutcome::kInvalidValue);
  const PipelineCounters& c = dirty.counters();
  EXPECT_EQ(c.zero_stamps, 1u);
  EXPECT_EQ(c.invalid_values, 5u);
  EXPECT_EQ(c.rejected_torque, 4u);
  EXPECT_EQ(c.rejected_preload, 2u);
  EXPECT_NE(c.last_event.find("no_such_bearing"), std::string::npos) << c.last_event;
  ASSERT_EQ(clean.torque(at(0.1), 0.2, a), InputOutcome::kAccepted);
  ASSERT_EQ(dirty.torque(at(0.1), 0.2, b), InputOutcome::kAccepted);
  ASSERT_EQ(a.te.size(), b.te.size());
  for (std::size_t i = 0; i < a.te.size(); ++i)
    EXPECT_EQ(a.te[i].dynamic_te, b.te[i].dynamic_te) << i;
  EXPECT_EQ(a.stiffness_out.back().second.supports[0].solution.radialStiffness(),
            b.stiffness_out.back().second.supports[0].solution.radialStiffness());
}

// The out-of-order and burst rules: a late stamp within ~stamp_jump_back is rejected (the dynamics
// cannot go back); equal stamps are accepted without releasing samples and the last torque is the
// one held; a stamp further back restarts everything and is then accepted.
TEST(RigPipeline, OutOfOrderBurstAndStampJumpBack) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  ASSERT_EQ(p.torque(at(1.0), 0.1, r), InputOutcome::kAccepted);
  ASSERT_EQ(p.torque(at(1.010), 0.1, r), InputOutcome::kAccepted);
  EXPECT_EQ(r.te.size(), 10u);  // (1.000, 1.010] on the 1 ms grid
  EXPECT_EQ(p.torque(at(1.005), 0.1, r), InputOutcome::kOutOfOrder);
  EXPECT_EQ(p.counters().out_of_order, 1u);
  const std::size_t before = r.te.size();
  for (double torque : {0.11, 0.12, 0.13})
    ASSERT_EQ(p.torque(at(1.010), torque, r), InputOutcome::kAccepted);
  EXPECT_EQ(r.te.size(), before);  // no time passed
  ASSERT_EQ(p.torque(at(1.012), 0.2, r), InputOutcome::kAccepted);
  ASSERT_EQ(r.te.size(), before + 2);
  EXPECT_EQ(r.te.back().torque, 0.13);  // zero-order hold of the last of the burst
  // Back by 2 s > ~stamp_jump_back (1 s): a restart, counted, and the input accepted.
  ASSERT_EQ(p.torque(at(-1.0), 0.1, r), InputOutcome::kAccepted);
  EXPECT_EQ(p.counters().stamp_resets, 1u);
  ASSERT_EQ(p.torque(at(-0.99), 0.1, r), InputOutcome::kAccepted);
  EXPECT_NEAR(r.te.back().t, at(-0.99).toSec(), 1e-6);
}

// The gap rule: a forward gap longer than ~max_gap restarts the dynamics instead of integrating it.
TEST(RigPipeline, LongGapRestartsTheDynamics) {
  PipelineOptions o;
  o.max_gap = 0.5;
  RigPipeline p(rig(), o);
  Recorder r;
  p.torque(at(0.0), 0.1, r);
  p.torque(at(0.1), 0.1, r);
  const std::size_t before = r.te.size();
  EXPECT_EQ(p.torque(at(10.0), 0.1, r), InputOutcome::kAccepted);
  EXPECT_EQ(r.te.size(), before);
  EXPECT_EQ(p.counters().gap_restarts, 1u);
  p.torque(at(10.003), 0.1, r);
  EXPECT_EQ(r.te.size(), before + 3);
}

// The gap rule before the own-stamp rule: after a gap the dynamics restart before a stiffness
// stamped after it is taken up. The last torque before the gap lies off the 1 ms output grid (the
// dynamics stand on the sample before it, its torque change pending), and the first after it moves
// a bearing stiffness by more than the 1 % at which the dynamics take a change up: applied at the
// time before the gap, that change would reach the dynamics as "before the current time" (a
// dynamics error) and the restart would keep the old stiffness. Each input is also tried as a
// preload, which takes the same path without a torque.
TEST(RigPipeline, AStiffnessChangeAfterAGapRestartsWithTheNewStiffness) {
  for (const bool by_preload : {false, true}) {
    RigPipeline p(rig(), PipelineOptions{});
    Recorder r;
    // A light preload, so that the mesh force moves the bearings' stiffness.
    const std::vector<PreloadSetting> light = {{"pinion_bearing", 100.0, 0.0, 0.0, 0.0},
                                               {"gear_bearing", 100.0, 0.0, 0.0, 0.0}};
    ASSERT_EQ(p.preload(at(0.0), light, r), InputOutcome::kAccepted);
    ASSERT_EQ(p.torque(at(0.0), 0.1, r), InputOutcome::kAccepted);
    ASSERT_EQ(p.torque(at(0.50041192), 0.1, r), InputOutcome::kAccepted);  // off the grid
    ASSERT_EQ(p.dynamics()->time(),
              0.5);  // on the sample before the stamp, the torque change pending
    const std::array<double, 2> before = p.dynamics()->bearingStiffness();
    // 1.5 s later (more than ~max_gap = 1 s), a load that moves the bearings by more than 1 %.
    const InputOutcome outcome =
        by_preload ? p.preload(at(2.0), preloads(3000.0), r) : p.torque(at(2.0), 8.0, r);
    ASSERT_EQ(outcome, InputOutcome::kAccepted);
    if (by_preload) {
      ASSERT_EQ(p.torque(at(2.001), 0.1, r), InputOutcome::kAccepted);
    }
    const std::array<double, 2> k = p.estimator().shaftRadialStiffness();
    ASSERT_GT(std::max(std::abs(k[0] / before[0] - 1.0), std::abs(k[1] / before[1] - 1.0)), 0.01)
        << "the case needs a change the dynamics take up: " << k[0] / before[0] << ", "
        << k[1] / before[1];
    EXPECT_EQ(p.counters().dynamics_errors, 0u) << p.counters().last_event;
    EXPECT_EQ(p.counters().gap_restarts, 1u);
    // The restarted dynamics run on the new stiffness (on the dynamics' 1 % grid).
    for (int i = 0; i < 2; ++i)
      EXPECT_NEAR(p.dynamics()->bearingStiffness()[i] / k[i], 1.0, 0.006) << i;
    ASSERT_EQ(p.torque(at(2.010), 0.1, r), InputOutcome::kAccepted);
    EXPECT_EQ(p.counters().dynamics_errors, 0u) << p.counters().last_event;
  }
}

// Every refusal is kept by stream and reason with the first one's stamp and reason and the values
// found, not only the last event.
TEST(RigPipeline, RefusalsAreTalliedByStreamAndReason) {
  PipelineOptions o;
  o.torque_frame = "pinion";
  RigPipeline p(rig(), o);
  Recorder r;
  const std::string bad_utf8 = "base\x85link";
  for (int i = 0; i < 5; ++i) p.torque(at(0.001 * (i + 1)), 0.1, r, {"/rig", 0, "base_link"});
  p.torque(at(0.010), 0.1, r, {"/rig", 0, bad_utf8});
  p.torque(at(0.011), std::numeric_limits<double>::quiet_NaN(), r, {"/rig", 0, "pinion"});
  p.motionRefused(at(0.012), "no joint named 'pinion' (~pinion_joint)", {},
                  "joints 'motor', 'output'");
  const RefusalTally& t = p.refusals();
  const RefusalTally::Entry& frame = t.entry(InputStream::kTorque, InputOutcome::kWrongFrame);
  EXPECT_EQ(frame.count, 6u);
  EXPECT_EQ(frame.first_stamp, at(0.001));
  EXPECT_NE(frame.first_reason.find("'base_link', expected ~torque_frame = 'pinion'"),
            std::string::npos)
      << frame.first_reason;
  ASSERT_EQ(frame.found.size(), 2u);
  EXPECT_EQ(frame.found[0].value, "base_link");
  EXPECT_EQ(frame.found[0].count, 5u);
  EXPECT_EQ(frame.found[1].value, "base\\x85link");  // printable: the byte escaped
  EXPECT_EQ(t.entry(InputStream::kTorque, InputOutcome::kInvalidValue).count, 1u);
  EXPECT_EQ(t.total(InputStream::kTorque), 7u);
  EXPECT_EQ(t.total(InputStream::kTorque), p.counters().rejected_torque);
  const RefusalTally::Entry& joints =
      t.entry(InputStream::kJointStates, InputOutcome::kInvalidValue);
  EXPECT_EQ(joints.count, 1u);
  ASSERT_EQ(joints.found.size(), 1u);
  EXPECT_EQ(joints.found[0].value, "joints 'motor', 'output'");
  // Past kMaxFound distinct values the rest are counted together.
  for (std::size_t i = 0; i < RefusalTally::kMaxFound + 3; ++i) {
    p.torque(at(0.1 + 0.001 * i), 0.1, r, {"/rig", 0, "frame" + std::to_string(i)});
  }
  EXPECT_EQ(t.entry(InputStream::kTorque, InputOutcome::kWrongFrame).found.size(),
            RefusalTally::kMaxFound);
  EXPECT_EQ(t.entry(InputStream::kTorque, InputOutcome::kWrongFrame).found_other, 5u);
}

// The clock-jump rule: the caller's clock going back (a looping bag) resets estimator and dynamics:
// the configured preloads return, and the replayed inputs are accepted again; a clock that only
// repeats itself does not reset.
TEST(RigPipeline, ClockJumpBackResetsEverything) {
  PipelineOptions o;
  o.clock_jump_back = 0.0;  // any step back (tf2's rule); the default is tested below
  RigPipeline p(rig(), o);
  Recorder r;
  const double configured_k = p.estimator().current().supports[0].solution.radialStiffness();
  p.observeClock(at(0.0), r);
  p.preload(at(0.0), preloads(2000.0), r);
  p.torque(at(0.0), 0.1, r);
  p.observeClock(at(0.5), r);
  p.torque(at(0.5), 0.1, r);
  EXPECT_FALSE(p.observeClock(at(0.5), r));
  EXPECT_GT(std::abs(p.estimator().current().supports[0].solution.radialStiffness() - configured_k),
            1e-3 * configured_k);
  EXPECT_TRUE(p.observeClock(at(0.0), r));
  EXPECT_EQ(p.counters().clock_resets, 1u);
  EXPECT_NEAR(p.estimator().current().supports[0].solution.radialStiffness(), configured_k,
              1e-9 * configured_k);
  EXPECT_FALSE(p.dynamics()->started());
  EXPECT_EQ(p.torque(at(0.0), 0.1, r), InputOutcome::kAccepted);  // the loop's first input again
  EXPECT_EQ(p.counters().out_of_order, 0u);
}

// The default ~clock_jump_back (1 s) keeps the state through an NTP-sized step back (0.5 s; ntpd
// steps offsets over 0.128 s): the inputs stamped in the repeated half second are out of order
// (rejected, counted), the stiffness estimate and the running dynamics stay; a looping bag's jump
// back by its 2 s length still resets everything.
TEST(RigPipeline, DefaultClockRuleTellsAnNtpStepFromALoopingBag) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  for (int k = 0; k <= 2000; ++k) {
    p.observeClock(at(1e-3 * k), r);
    p.torque(at(1e-3 * k), 0.1, r);
  }
  ASSERT_TRUE(p.dynamics()->started());
  EXPECT_FALSE(p.observeClock(at(1.5), r));  // stepped back by 0.5 s
  EXPECT_EQ(p.torque(at(1.5), 0.1, r), InputOutcome::kOutOfOrder);
  EXPECT_TRUE(p.dynamics()->started());
  EXPECT_EQ(p.counters().clock_resets, 0u);
  EXPECT_EQ(p.counters().out_of_order, 1u);
  EXPECT_EQ(p.torque(at(2.001), 0.1, r), InputOutcome::kAccepted);  // caught up
  EXPECT_TRUE(p.observeClock(at(0.0), r));                          // the bag looped
  EXPECT_EQ(p.counters().clock_resets, 1u);
  EXPECT_FALSE(p.dynamics()->started());
}

// Same inputs, same order: bit-identical outputs (what makes drivetrain_replay reproducible).
TEST(RigPipeline, Deterministic) {
  auto run = [] {
    RigPipeline p(rig(), PipelineOptions{});
    Recorder r;
    p.preload(at(0.0), preloads(800.0), r);
    for (int k = 0; k < 400; ++k) p.torque(at(k * 1e-3), 0.1 + 0.01 * std::sin(0.7 * k), r);
    p.preload(at(0.4), preloads(1500.0), r);
    for (int k = 400; k < 800; ++k) p.torque(at(k * 1e-3), 0.1 + 0.01 * std::sin(0.7 * k), r);
    return r;
  };
  const Recorder a = run(), b = run();
  ASSERT_EQ(a.te.size(), b.te.size());
  for (std::size_t i = 0; i < a.te.size(); ++i) {
    EXPECT_EQ(a.te[i].t, b.te[i].t);
    EXPECT_EQ(a.te[i].dynamic_te, b.te[i].dynamic_te);
  }
  ASSERT_EQ(a.resonance_out.size(), b.resonance_out.size());
  EXPECT_GE(a.resonance_out.size(), 2u);  // the 800 -> 1500 N preload step moves the modes > 1 %
}

// The resonance shortcut (skip the modal analysis while every spring is within (1 -+ tau)^2 of its
// value at the last publication; Courant-Fischer bounds the frequencies) must publish exactly
// when an analysis at every input would have: recompute the modes here for every accepted input
// with an independent estimator and apply the threshold rule by hand.
TEST(RigPipeline, ResonanceShortcutPublishesExactlyWhenTheFullRuleWould) {
  PipelineOptions o;
  o.limits.load_tolerance = 0.0;  // the independent estimator below re-solves every input
  RigPipeline p(rig(), o);
  Recorder r;
  StiffnessEstimator reference(rig(), o.limits);
  std::vector<Stamp> expected;
  std::vector<double> published;
  auto check = [&](Stamp s, const StiffnessEstimate& e) {
    const std::array<double, 2> kb = reference.shaftRadialStiffness();
    const std::array<Mode, 3> modes =
        modalAnalysis(rigRotorParameters(rig(), reference.mesh(), kb), e.mesh.mean);
    bool moved = published.empty();
    for (std::size_t i = 0; !moved && i < 3; ++i) {
      moved = std::abs(modes[i].natural_frequency - published[i]) >
              o.resonance_threshold * published[i];
    }
    if (!moved) return;
    published = {modes[0].natural_frequency, modes[1].natural_frequency,
                 modes[2].natural_frequency};
    expected.push_back(s);
  };
  const double omega = 1000.0 * 2.0 * M_PI / 60.0;
  for (int k = 0; k < 200; ++k) {
    const double t = 0.02 * k;
    if (k % 10 == 0) {
      const double axial = 200.0 + 9.0 * k;  // 200 -> 1991 N: a preload ramp
      ASSERT_EQ(p.preload(at(t), preloads(axial), r), InputOutcome::kAccepted);
      check(at(t), reference.setPreloads(preloads(axial)));
    }
    const double torque =
        0.1 + 0.4 * std::sin(0.05 * k);  // large swings: the bearing load moves too
    ASSERT_EQ(p.torque(at(t), torque, r), InputOutcome::kAccepted);
    check(at(t), reference.setTorque(torque, omega * t));
  }
  ASSERT_EQ(r.resonance_out.size(), expected.size());
  EXPECT_GE(expected.size(), 5u);  // the ramp moves f1 by several per cent
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_EQ(r.resonance_out[i].first.ns, expected[i].ns) << i;
  EXPECT_LT(p.counters().modal_updates, 400u);  // and it did skip analyses (400 accepted inputs)
  // Nor is it much more cautious than it must be: springs within (1 -+ tau)^2 bound the frequencies
  // within 1 -+ tau, so an analysis seldom finds nothing to publish (15 for 15 here; the factors
  // 1 +- tau of until 2026-11-26 ran 73 analyses for the same 15 publications).
  EXPECT_LE(p.counters().modal_updates, 2 * r.resonance_out.size());
}

// The bearing shortcut (~bearing_load_tolerance): between re-solves the stiffness lags the exact
// one; for Hertz contact (k ~ Q^(1/3)) the lag is about tol / 3 of the support's load share.
TEST(RigPipeline, BearingLoadToleranceBoundsTheStiffnessLag) {
  EstimatorLimits exact_limits, shortcut_limits;
  shortcut_limits.load_tolerance = 1e-3;
  StiffnessEstimator exact(rig(), exact_limits), shortcut(rig(), shortcut_limits);
  double worst = 0.0;
  int skipped = 0;
  for (int k = 0; k < 2000; ++k) {
    const double torque = 0.1 * (1.0 + 0.05 * std::sin(2 * M_PI * 100.0 * k * 1e-3));  // 5 % ripple
    const double angle = 0.37 * k;  // [rad] the mesh phase moves every input
    const double ke = exact.setTorque(torque, angle).supports[0].solution.radialStiffness();
    const StiffnessEstimate& s = shortcut.setTorque(torque, angle);
    skipped += s.supports[0].radial_load != exact.current().supports[0].radial_load;
    worst = std::max(worst, std::abs(s.supports[0].solution.radialStiffness() - ke) / ke);
    // The shortcut (updated in place when every support's solution stands) skips only the bearing
    // solves: torque, mesh force and mesh do not depend on the tolerance and must equal the exact
    // ones.
    const StiffnessEstimate& e = exact.current();
    ASSERT_EQ(s.torque, e.torque) << k;
    ASSERT_EQ(s.mesh_force, e.mesh_force) << k;
    ASSERT_EQ(s.mesh.phase, e.mesh.phase) << k;
    ASSERT_EQ(s.mesh.current.composite, e.mesh.current.composite) << k;
    ASSERT_EQ(s.mesh.mean, e.mesh.mean) << k;
  }
  EXPECT_GT(skipped, 1000);      // the shortcut is taken for most inputs of a 5 % ripple...
  EXPECT_LT(worst, 1e-3 / 3.0);  // ...and the stiffness stays within tol / 3 of the exact solve
  EXPECT_GT(worst, 0.0);
}

// Fidelities switch at run time on the same grid; quasi-static means the torsional mode is in
// equilibrium, so the predicted deflection equals the static one F / k_s exactly
// (reduced_models.hpp).
TEST(RigPipeline, FidelityAndDampingSwitchAtRunTime) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  p.torque(at(0.0), 0.1, r);
  p.torque(at(0.05), 0.1, r);
  RuntimeSettings s = p.settings();
  s.fidelity = Fidelity::kQuasiStatic;
  p.apply(s);
  p.torque(at(0.1), 0.1, r);
  ASSERT_EQ(r.te.size(), 100u);
  for (std::size_t i = 50; i < 100; ++i) {
    EXPECT_NEAR(r.te[i].dynamic_te, r.te[i].static_te, 1e-12 * std::abs(r.te[i].static_te)) << i;
  }
  EXPECT_EQ(r.te_stamps[99].ns - r.te_stamps[49].ns, 50000000);  // the grid continues, exactly
  s.fidelity = Fidelity::kFull;
  s.mesh_damping_ratio = 0.1;
  s.bearing_damping_ratio = 0.05;
  p.apply(s);
  const std::size_t published = r.resonance_out.size();
  p.torque(at(0.11), 0.1, r);
  ASSERT_EQ(r.te.size(), 110u);
  // The mesh phase continues across the rebuild: 1 ms steps of 1/3 of the 3 ms mesh period.
  EXPECT_NEAR(std::fmod(r.te[100].phase - r.te[99].phase + 1.0, 1.0), 1.0 / 3.0, 1e-9);
  // Refused whole: a bad damping ratio leaves the fidelity change beside it unapplied too.
  RuntimeSettings bad = s;
  bad.fidelity = Fidelity::kQuasiStatic;
  bad.bearing_damping_ratio = 2.0;
  EXPECT_THROW(p.apply(bad), InvalidInput);
  EXPECT_EQ(p.settings().fidelity, Fidelity::kFull);
  bad.bearing_damping_ratio = -0.1;
  EXPECT_THROW(p.apply(bad), InvalidInput);
  // Each refusal names the ratio that is out of range (fuzz finding: "damping ratios (1.5, 0)").
  for (const auto& [mesh, bearing, named] : {std::tuple{1.5, 0.0, "mesh_damping_ratio = 1.5"},
                                             std::tuple{0.0, 2.0, "bearing_damping_ratio = 2"}}) {
    RuntimeSettings spoiled = s;
    spoiled.mesh_damping_ratio = mesh;
    spoiled.bearing_damping_ratio = bearing;
    try {
      p.apply(spoiled);
      ADD_FAILURE() << "accepted " << named;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  }
  // A damping change republishes the resonance at the next input with the new ratios.
  ASSERT_EQ(r.resonance_out.size(), published + 1);
  EXPECT_NEAR(r.resonance_out.back().second.modes[2].damping_ratio, 0.1,
              0.02);  // the torsional mode
}

// The run-time settings are checked in one place with the ranges of cfg/Estimator.cfg, naming the
// field; the same check runs at start-up, on reconfiguration and in the replay.
TEST(RuntimeSettings, OneValidationNamesTheField) {
  const std::vector<std::pair<std::string, std::function<void(RuntimeSettings&)>>> bad = {
      {"mesh_damping_ratio", [](RuntimeSettings& s) { s.mesh_damping_ratio = 1.5; }},
      {"bearing_damping_ratio", [](RuntimeSettings& s) { s.bearing_damping_ratio = std::nan(""); }},
      {"stiffness_rate", [](RuntimeSettings& s) { s.stiffness_rate = 1e9; }},
      {"exaggeration", [](RuntimeSettings& s) { s.exaggeration = 0.5; }},
      {"tf_rate", [](RuntimeSettings& s) { s.tf_rate = -1.0; }},
  };
  for (const auto& [field, spoil] : bad) {
    RuntimeSettings s;
    spoil(s);
    try {
      s.validate();
      ADD_FAILURE() << field << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()).rfind(field + " = ", 0), 0u) << e.what();
    }
    EXPECT_THROW(RigPipeline(rig(), PipelineOptions{}, s), InvalidInput) << field;
  }
  RuntimeSettings::forRig(rig()).validate();  // the gearbox's own values pass
}

// Stiffness coalescing (~stiffness_rate) is decided on stamps, so a replay coalesces the same way,
// and every input is still counted.
TEST(RigPipeline, StiffnessRateCoalescesOnStamps) {
  PipelineOptions o;
  RuntimeSettings settings = RuntimeSettings::forRig(rig());
  settings.stiffness_rate = 100.0;
  RigPipeline p(rig(), o, settings);
  Recorder r;
  for (int k = 0; k < 1000; ++k) p.torque(at(k * 1e-3), 0.1, r);
  EXPECT_EQ(r.stiffness_out.size(), 100u);
  EXPECT_EQ(p.counters().stiffness_out + p.counters().stiffness_coalesced, 1000u);
  EXPECT_EQ(p.counters().accepted_torque, 1000u);
}

// From an independent review: a bad value never acts through its stamp (no reset from a NaN with an
// old stamp), and a rejected first torque does not set the mesh-phase origin.
TEST(RigPipeline, BadValuesNeverActThroughTheirStamps) {
  RigPipeline p(rig(), PipelineOptions{}), fresh(rig(), PipelineOptions{});
  Recorder r, f;
  EXPECT_EQ(p.torque(at(5.0), std::numeric_limits<double>::quiet_NaN(), r),
            InputOutcome::kInvalidValue);
  ASSERT_EQ(p.torque(at(5.7), 0.1, r), InputOutcome::kAccepted);
  ASSERT_EQ(fresh.torque(at(5.7), 0.1, f), InputOutcome::kAccepted);
  EXPECT_EQ(r.stiffness_out.back().second.mesh.phase,
            f.stiffness_out.back().second.mesh.phase);  // origin 5.7, not 5.0
  p.preload(at(5.8), preloads(1500.0), r);
  const double k = p.estimator().current().supports[0].solution.radialStiffness();
  EXPECT_EQ(p.torque(at(2.0), std::numeric_limits<double>::infinity(), r),
            InputOutcome::kInvalidValue);  // 3.7 s back
  EXPECT_EQ(p.preload(at(2.0), preloads(-1.0), r), InputOutcome::kInvalidValue);
  EXPECT_EQ(p.counters().stamp_resets, 0u);
  EXPECT_EQ(p.estimator().current().supports[0].solution.radialStiffness(),
            k);  // preloads not reset
}

// ~pinion_speed_rpm drives the dynamics too (one speed for both mesh phases): at 2000 rpm the
// 20-tooth pinion meshes at 666.7 Hz, so 1 kHz rounds to two samples per 1.5 ms period.
TEST(RigPipeline, PinionSpeedReachesTheDynamics) {
  PipelineOptions o;
  o.pinion_speed_rpm = 2000.0;
  RigPipeline p(rig(), o);
  EXPECT_NEAR(p.dynamics()->outputInterval(), 0.75e-3, 1e-12);
  Recorder r;
  p.torque(at(0.0), 0.1, r);
  p.torque(at(0.003), 0.1, r);
  ASSERT_EQ(r.te.size(), 4u);
  EXPECT_NEAR(std::fmod(r.te[2].phase - r.te[1].phase + 1.0, 1.0), 0.5, 1e-9);
  o.pinion_speed_rpm = 0.0;
  EXPECT_THROW(RigPipeline(rig(), o), InvalidInput);
}

// A looping bag whose first messages beat its /clock jump: the stamp rule restarts first, and the
// clock jump that follows does not reset a second time (the preload of the new loop survives).
TEST(RigPipeline, LoopStampsBeforeClockResetOnce) {
  RigPipeline p(rig(), PipelineOptions{});
  Recorder r;
  p.observeClock(at(0.0), r);
  p.preload(at(0.0), preloads(800.0), r);
  p.torque(at(0.0), 0.1, r);
  p.observeClock(at(3.0), r);
  p.preload(at(2.0), preloads(800.0), r);  // re-sent, as rigs do
  p.torque(at(3.0), 0.1, r);
  // The loop restarts: its preload arrives before the clock says so.
  ASSERT_EQ(p.preload(at(0.0), preloads(1500.0), r), InputOutcome::kAccepted);
  EXPECT_EQ(p.counters().stamp_resets, 1u);
  const double k = p.estimator().current().supports[0].solution.radialStiffness();
  EXPECT_FALSE(p.observeClock(at(0.01), r));
  EXPECT_EQ(p.counters().clock_resets, 0u);
  EXPECT_EQ(p.estimator().current().supports[0].solution.radialStiffness(), k);
}

// One rule per setting: every entry that takes a value refuses the same values
// with a message naming its field, and accepts the same edges.
namespace {

// The message of the InvalidInput `f` throws, or "" (and a failure) when it accepts.
template <typename F>
std::string refusalOf(F f, const std::string& what) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  ADD_FAILURE() << what << " accepted";
  return {};
}

// seed_servo.yaml with the dynamics block's `key` set to `value`, written beside the test's files
// (its bearing files referenced by absolute path).
std::string gearboxWith(const std::string& key, const std::string& value) {
  const std::string source = DRIVETRAIN_SOURCE_DIR;
  std::ifstream in(source + "/config/gearboxes/seed_servo.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (std::size_t at; (at = text.find("../bearings/")) != std::string::npos;)
    text.replace(at, 12, source + "/config/bearings/");
  const std::size_t line = text.find("  " + key + ":");
  EXPECT_NE(line, std::string::npos) << key;
  text.replace(line, text.find('\n', line) - line, "  " + key + ": " + value);
  const std::string path = testing::TempDir() + "one_rule_" + key + ".yaml";
  std::ofstream(path) << text;
  return path;
}

}  // namespace

// The damping ratios: [0, 1] (kMaxDampingRatio, core/rig_model.hpp) from the gearbox YAML, the
// run-time settings (parameters, dynamic_reconfigure, replay) and DynamicsEstimator::setDamping.
TEST(OneRule, DampingRatioIsTheSameFromEveryEntry) {
  for (const std::string field : {"mesh_damping_ratio", "bearing_damping_ratio"}) {
    const std::pair<const char*, double> refused[] = {
        {"-0.01", -0.01}, {"1.000001", 1.000001}, {"1.5", 1.5}};
    for (const auto& [text, value] : refused) {
      const std::string named = field + " = " + formatValue(value);
      const std::string path = gearboxWith(field, text);
      const std::string yaml = refusalOf([&] { loadRigFile(path); }, "YAML " + named);
      EXPECT_EQ(yaml.rfind(path + ": ", 0), 0u) << yaml;
      EXPECT_NE(yaml.find("dynamics." + named + ": must lie in [0, 1]"), std::string::npos) << yaml;
    }
    for (const double value : {-0.01, 1.000001, 1.5, std::nan("")}) {
      const std::string named = field + " = " + formatValue(value);
      RuntimeSettings s;
      (field == "mesh_damping_ratio" ? s.mesh_damping_ratio : s.bearing_damping_ratio) = value;
      const std::string settings = refusalOf([&] { s.validate(); }, "settings " + named);
      EXPECT_EQ(settings.rfind(named + ": must ", 0), 0u) << settings;
      DynamicsEstimator est(rig(), {1.2e8, 1.2e8}, 1000.0);
      const std::string set = refusalOf(
          [&] {
            field == "mesh_damping_ratio" ? est.setDamping(value, 0.02)
                                          : est.setDamping(0.05, value);
          },
          "setDamping " + named);
      EXPECT_EQ(set, settings);
    }
    // The edges pass everywhere; 1 (critical damping of the mode the ratio is defined on) runs:
    // the exact propagation hands an ill-conditioned eigenbasis to dopri5, and the samples stay
    // finite.
    for (const double value : {0.0, 1.0}) {
      const std::string text = value == 0.0 ? "0" : "1";
      const RigConfig loaded = loadRigFile(gearboxWith(field, text));
      RuntimeSettings s = RuntimeSettings::forRig(loaded);
      EXPECT_EQ(field == "mesh_damping_ratio" ? s.mesh_damping_ratio : s.bearing_damping_ratio,
                value);
      EXPECT_NO_THROW(s.validate());
      DynamicsEstimator est(rig(), {1.2e8, 1.2e8}, 1000.0);
      est.reset(0.0, 0.1);
      std::size_t samples = 0;
      est.advanceTo(0.05, [&](const DynamicsSample&) {});
      EXPECT_NO_THROW(field == "mesh_damping_ratio" ? est.setDamping(value, 0.02)
                                                    : est.setDamping(0.05, value));
      est.advanceTo(0.1, [&](const DynamicsSample& d) {
        ++samples;
        EXPECT_TRUE(d.state.allFinite()) << field << " " << value;
      });
      EXPECT_GT(samples, 40u);
    }
  }
}

// The bearing load tolerance: [0, 0.1] (kMaxLoadTolerance) from the pipeline's options
// (~bearing_load_tolerance) and StiffnessEstimator, each naming the field its user knows.
TEST(OneRule, LoadToleranceIsTheSameFromEveryEntry) {
  for (const double value : {-1e-3, 0.100001, 0.5, std::nan("")}) {
    PipelineOptions o;
    o.limits.load_tolerance = value;
    const std::string v = formatValue(value);
    const std::string options = refusalOf([&] { o.validate(); }, "options " + v);
    EXPECT_EQ(options.rfind("bearing_load_tolerance = " + v + ": must ", 0), 0u) << options;
    // The same refusal, under the estimator's own name for the field.
    EXPECT_EQ("bearing_" +
                  refusalOf([&] { (void)StiffnessEstimator(rig(), o.limits); }, "estimator " + v),
              options);
  }
  for (const double value : {0.0, 0.1}) {
    PipelineOptions o;
    o.limits.load_tolerance = value;
    EXPECT_NO_THROW(o.validate());
    EXPECT_NO_THROW((void)StiffnessEstimator(rig(), o.limits));
  }
}

// The input limits (~max_abs_torque, ~max_preload, ~max_interference): one rule
// (EstimatorLimits::validate) from the options and from the estimator, with the same refusal.
TEST(OneRule, InputLimitsAreTheSameFromEveryEntry) {
  using Field = double EstimatorLimits::*;
  const std::pair<const char*, Field> fields[] = {
      {"max_abs_torque", &EstimatorLimits::max_abs_torque},
      {"max_preload", &EstimatorLimits::max_preload},
      {"max_interference", &EstimatorLimits::max_interference}};
  for (const auto& [name, field] : fields) {
    for (const double value : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
      PipelineOptions o;
      o.limits.*field = value;
      const std::string v = formatValue(value);
      const std::string options =
          refusalOf([&] { o.validate(); }, std::string("options ") + name + " " + v);
      EXPECT_EQ(options.rfind(std::string(name) + " = " + v + ": must ", 0), 0u) << options;
      EXPECT_EQ(refusalOf([&] { (void)StiffnessEstimator(rig(), o.limits); },
                          std::string("estimator ") + name),
                options);
    }
  }
}

// The display scale: [1, 1e8] (requireExaggeration, runtime_settings.hpp) from the settings; the
// visualizer calls the same check (test/ros/test_rig_visualization.cpp).
TEST(OneRule, ExaggerationIsTheSameFromTheSettingsAndItsCheck) {
  for (const double value : {0.999, 1.0000001e8, -1.0, std::nan("")}) {
    RuntimeSettings s;
    s.exaggeration = value;
    const std::string message = refusalOf([&] { s.validate(); }, "settings");
    EXPECT_EQ(message.rfind("exaggeration = " + formatValue(value) + ": must ", 0), 0u) << message;
    EXPECT_EQ(refusalOf([&] { requireExaggeration(value); }, "check"), message);
  }
  for (const double value : {1.0, 1e8}) {
    RuntimeSettings s;
    s.exaggeration = value;
    EXPECT_NO_THROW(s.validate());
  }
}

// The per-input hot path allocates nothing in steady state: a counting global operator new (this
// binary only) around torque inputs to a warmed-up RigPipeline with full dynamics (bearing solves,
// mesh lookup, dynamics, TE spectrum, resonance check), solved in full or shed; and preload
// inputs between them (supports rebuilt and re-solved, the dynamics' bearing stiffness changed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "counting_new.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "ripple_torque_feed.hpp"  // NOLINT(build/include_subdir)
#include "seed_rig.hpp"            // NOLINT(build/include_subdir)
#include "static_te_encoder.hpp"   // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;
using test::allocationCount;

namespace {

// Torque inputs to a warmed-up pipeline (2 s of 10 kHz inputs: tables, propagators, a full
// spectrum window), then 1 s more counted: none may allocate.
long allocationsPerSecondOfInputs(const PipelineOptions& options, Backlog backlog) {
  RigPipeline pipeline(test::seedServo(), options);
  RippleTorqueFeed feed(pipeline);
  for (int i = 0; i < 20000; ++i) feed.next();
  const long before = allocationCount();
  for (int i = 0; i < 10000; ++i) feed.next(backlog);
  return allocationCount() - before;
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
  const long before = allocationCount();
  for (int k = 1000; k < 2000; ++k) step(k);
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 2e3 << " heap allocations per input";
  EXPECT_EQ(pipeline.counters().accepted_motion, 2000u);
  EXPECT_STREQ(pipeline.phaseSource(), "encoders");
}

// The live calibration (the calibration rule) on the per-reading path: torque at 1 kHz and
// joint_states with both joints at 5 kHz, 120 rpm, the gear angle carrying the static model's TE
// (so loaded windows pass the gate and run the whole update: fit, iterated EKF, bands, modal
// analyses). Warmed up through a baseline and the first loaded windows, then 2 s (two gear turns,
// two updates) counted.
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
    pipeline.motion(Stamp{test::kEpoch + 200000LL * k + 100000LL},
                    encoder.reading(w * t, w, torque), sink);
  };
  for (int k = 0; k < 25000; ++k) step(k);  // 5 s: baseline, then loaded windows
  const std::uint64_t updates_before = pipeline.calibrator()->estimate().updates;
  const long before = allocationCount();
  for (int k = 25000; k < 35000; ++k) step(k);
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 1e4 << " heap allocations per reading";
  EXPECT_GE(pipeline.calibrator()->estimate().updates, updates_before + 2);
  EXPECT_EQ(pipeline.calibrator()->estimate().gated, 0u);
}

// The calibration's record of its progress (Calibrator::progress, what waitingReason explains) is
// kept on the per-reading path too: windows dropped at torque steps and at breaks in the readings,
// and the progress read back, allocate nothing. The Calibrator alone, 60 rpm at 5 kHz, steps of
// 1.5 s (short of the 2 s gear turn) between 0 and 2 N m, a break every 0.7 s; warmed up by the
// same cycle once, then a second cycle counted.
TEST(NoAllocation, CalibrationProgressThroughDroppedWindows) {
  RigConfig rig = test::seedServo();
  rig.calibration.present = true;
  Calibrator calibrator(rig);
  StiffnessEstimator supports(rig);
  const test::StaticTeEncoder encoder(rig, 2.0);
  const double w = 2.0 * M_PI;  // 60 rpm
  MeasuredTeSample sample;
  double longest = 0.0;
  auto cycle = [&](long first) {
    for (long k = first; k < first + 30000; ++k) {  // 6 s
      const double t = 2e-4 * k, theta = w * t;
      const double torque = static_cast<long>(t / 1.5) % 2 == 0 ? 0.0 : 2.0;
      if (k % 3500 == 0) calibrator.interrupt();
      calibrator.reading(t, theta, encoder.gearAngle(theta, torque), encoder.phase(theta), w,
                         torque, supports, sample);
      longest = std::max(longest, calibrator.progress().loaded.duration);
    }
  };
  cycle(0);
  const long before = allocationCount();
  cycle(30000);
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 3e4 << " heap allocations per reading";
  EXPECT_EQ(calibrator.estimate().windows, 0u);
  EXPECT_GT(longest, 0.5);
  EXPECT_LT(longest, 1.5);
}

// The calibration's updates from identified natural frequencies (Calibrator::modalUpdate): per
// record a few modal analyses, the iterated update and the outputs in fixed-size storage. Warmed up
// by one record, then ten records counted: updated, gated and empty ones.
TEST(NoAllocation, NaturalFrequencyRecordsThroughCalibrationUpdates) {
  RigConfig rig = test::seedServo();
  rig.calibration.present = true;
  Calibrator calibrator(rig);
  StiffnessEstimator supports(rig);
  supports.setTorque(2.0);
  const std::array<Mode, 3> model = calibrator.modes(2.0, supports);
  // A rig whose transverse modes sit 1 % above and 2 % below the drawing's.
  const std::array<ModalFrequency, 2> record{
      {{0, 1.01 * model[0].natural_frequency, 4.0}, {1, 0.98 * model[1].natural_frequency, 5.0}}};
  const ModalFrequency outlier{1, 3.0 * model[1].natural_frequency, 5.0};
  ASSERT_EQ(calibrator.modalUpdate(0.5, record.data(), 2, 2.0, supports), WindowOutcome::kUpdated);
  const long before = allocationCount();
  int updated = 0, gated = 0;
  for (int i = 1; i <= 10; ++i) {
    const WindowOutcome o = i % 5 == 0 ? calibrator.modalUpdate(i, &outlier, 1, 2.0, supports)
                            : i % 7 == 0
                                ? calibrator.modalUpdate(i, nullptr, 0, 2.0, supports)
                                : calibrator.modalUpdate(i, record.data(), 2, 2.0, supports);
    updated += o == WindowOutcome::kUpdated;
    gated += o == WindowOutcome::kGated;
  }
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 10.0 << " heap allocations per record";
  EXPECT_EQ(updated, 7);
  EXPECT_EQ(gated, 2);
}

// Preload inputs: new axial and radial preloads and interferences for both
// supports at 20 Hz between torque inputs at 10 kHz. "Steady state" here means what a running rig
// reaches and keeps until a reset or an input gap restarts the dynamics:
//  - 2 s of torque inputs, as above (tables, propagators, a full spectrum window);
//  - one pass of the same preload cycle. Its first input that moves the bearing stiffness by more
//    than 1 % while the dynamics run switches them, once, from the periodic propagators to the
//    sliced propagation (DynamicsEstimator::parametersChanged: the sliced mesh, its propagator and
//    the model over it are made then and kept until a restart); every later change stays on it.
//    That switch is a one-time set-up, like the tables, so it belongs to the warm-up (as does the
//    first sizing of each kept parameter set's slices).
// Counted: 1 s more of the cycle. It changes the geometry of the supports (axial preload and
// interference: each support's Hertz model rebuilt and cold-started), the radial preload alone
// (warm-started), steps that move the bearing stiffness past the dynamics' 1 % (sliced
// propagator's parameters changed; the cycle's stiffnesses come back to the same values of the
// dynamics' 1 % grid, whose slices are kept, so here they are taken back; the
// decomposition of values never met before is BearingChangesToNewValuesInSteadyState below) and
// one that does not, and the resonance estimate each time; never the number of balls in contact
// (the per-ball storage is sized by the bearing's ball count, not by the balls in contact, but a
// step that changes the count is not what this case claims). The preload vectors are the caller's
// (the ROS message conversion builds them), made before counting. What would allocate per input:
// name strings in the checks, a copy of the supports, new Hertz models, a new estimate, a new model
// over the sliced mesh.
TEST(NoAllocation, PreloadInputsInSteadyState) {
  RigPipeline pipeline(test::seedServo(), PipelineOptions{});
  ReadingSink sink;
  const RigConfig& rig = test::seedServo();
  ASSERT_EQ(rig.bearings.size(), 2u);
  // Axial [N], radial [N], interference inner and outer [m], for both supports.
  struct Step {
    double axial, radial, inner, outer;
  };
  const Step cycle[] = {
      // Radial stiffness of each support after the step (seed gearbox, 0.1 N*m), and whether it
      // moves the dynamics (more than 1 %):
      {1100.0, 1000.0, 5e-6, 5e-6},  // axial preload +10 %: 1.265e8 N/m (+4.7 %), rebuilt
      {1100.0, 1050.0, 5e-6, 5e-6},  // radial only (warm start): 1.251e8 (-1.1 %)
      {1100.0, 1050.0, 6e-6, 5e-6},  // inner interference: 1.261e8 (+0.8 %), dynamics untouched
      {1101.0, 1050.0, 6e-6, 5e-6},  // +1 N axial: 1.262e8 (+0.04 %), dynamics untouched
      {1200.0, 950.0, 6e-6, 6e-6},   // everything at once: 1.339e8 (+6.1 %)
      {1000.0, 1000.0, 5e-6, 5e-6},  // back to the gearbox file's values: 1.209e8 (-9.8 %)
  };
  std::vector<std::vector<PreloadSetting>> messages;
  for (const Step& s : cycle) {
    std::vector<PreloadSetting> m;
    for (const BearingSupportConfig& b : rig.bearings)
      m.push_back({b.name, s.axial, s.radial, s.inner, s.outer});
    messages.push_back(std::move(m));
  }
  std::vector<int> balls;  // balls in contact per support at the last preload input
  bool same_balls = true;
  std::size_t next_message = 0;
  // k: 10 kHz ticks; with `preloads`, a preload input 50 us after every 500th torque input.
  auto step = [&](long k, bool preloads) {
    const double t = 1e-4 * static_cast<double>(k);
    pipeline.torque(Stamp{test::kEpoch + 100000LL * k},
                    0.1 * (1.0 + 0.1 * std::sin(2.0 * M_PI * 100.0 * t)), sink);
    if (!preloads || k % 500 != 0) return;
    pipeline.preload(Stamp{test::kEpoch + 100000LL * k + 50000LL}, messages[next_message], sink);
    next_message = (next_message + 1) % messages.size();
    const StiffnessEstimate& e = pipeline.estimator().current();
    for (std::size_t i = 0; i < e.supports.size(); ++i) {
      if (i < balls.size())
        same_balls = same_balls && e.supports[i].solution.balls_in_contact == balls[i];
    }
    balls.resize(e.supports.size());  // sized at the first preload input (warm-up), never after
    for (std::size_t i = 0; i < e.supports.size(); ++i)
      balls[i] = e.supports[i].solution.balls_in_contact;
  };
  for (long k = 0; k < 20000; ++k) step(k, false);  // 2 s of torque
  ASSERT_NE(pipeline.dynamics(), nullptr);
  ASSERT_FALSE(pipeline.dynamics()->followingMotion());  // on the periodic propagators until...
  for (long k = 20000; k < 23000; ++k) step(k, true);    // ...one preload cycle (6 inputs at 20 Hz)
  ASSERT_TRUE(pipeline.dynamics()->followingMotion());   // switched to the sliced propagation
  const PipelineCounters before_counters = pipeline.counters();
  const long dynamics_changes_before = pipeline.dynamics()->work().rebuilds;
  const long before = allocationCount();
  for (long k = 23000; k < 33000; ++k)
    step(k, true);  // 1 s: 20 preload inputs, 10000 torque inputs
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 20.0
                  << " heap allocations per preload input (with 500 torque inputs each)";
  const PipelineCounters& c = pipeline.counters();
  EXPECT_EQ(c.accepted_preload - before_counters.accepted_preload, 20u);
  EXPECT_EQ(c.accepted_torque - before_counters.accepted_torque, 10000u);
  EXPECT_EQ(c.rejected_preload + c.rejected_torque + c.dynamics_errors, 0u) << c.last_event;
  EXPECT_TRUE(same_balls) << "a preload step changed the number of balls in contact";
  // The dynamics' bearing stiffness changed during the counted second (4 of the 6 steps move it
  // past 1 %: 14 of the 20 inputs), and they stayed on the sliced propagation.
  EXPECT_EQ(pipeline.dynamics()->work().rebuilds - dynamics_changes_before, 14);
  EXPECT_TRUE(pipeline.dynamics()->followingMotion());
  EXPECT_GT(c.modal_updates, before_counters.modal_updates);
}

// Bearing changes to stiffnesses never met before, with the dynamics on the sliced propagation:
// each empties the longest unused of the propagator's kept parameter sets
// (SlicedModalPropagator::kKeptParameterSets) and decomposes its slices again as they are crossed,
// in the slice storage that set already has. Warm-up: 2 s of torque, then eight new stiffnesses
// (more than the six sets: every set sized, and eviction under way). Counted: twenty more, each a
// grid value not met before (2 % apart), 2 ms of torque inputs at 10 kHz after each (a period at
// 1000 rpm is 3 ms: about two thirds of the slices decomposed per change).
TEST(NoAllocation, BearingChangesToNewValuesInSteadyState) {
  DynamicsEstimator est(test::seedServo(), {1.2e8, 1.2e8}, 1000.0);
  est.reset(0.0, 0.1);
  double t = 0.0;
  auto run = [&](double until) {
    for (; t < until - 1e-12; t += 1e-4) {
      est.advanceTo(t, nullptr);
      est.setTorque(0.1 * (1.0 + 0.1 * std::sin(2.0 * M_PI * 100.0 * t)), t);
    }
  };
  long change = 0;
  auto newStiffness = [&] {
    const double k =
        1.2e8 * std::pow(1.02, static_cast<double>(++change % 40) - 20.0);  // 40 values, 2 % apart
    est.advanceTo(t, nullptr);
    est.setBearingStiffness({k, k}, t);
  };
  run(2.0);
  for (int i = 0; i < 8; ++i) {
    newStiffness();
    run(t + 2e-3);
  }
  ASSERT_TRUE(est.followingMotion());
  const long decompositions_before = est.work().decompositions, before = allocationCount();
  for (int i = 0; i < 20; ++i) {
    newStiffness();
    run(t + 2e-3);
  }
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 20.0 << " heap allocations per bearing change";
  EXPECT_GT(est.work().decompositions - decompositions_before, 20 * 100)
      << "the changes did not decompose slices";
}

/// A pipeline fed 1024-sample vibration blocks at 51.2 kHz (block k stamped 10 s + k blocks), with
/// a torque input at each block when `with_torque`.
struct VibrationFeed {
  VibrationFeed(std::vector<std::string> names, const PipelineOptions& options,
                std::optional<float> constant = std::nullopt)
      : pipeline(test::seedServo(), options), channels(std::move(names)) {
    data.resize(1024 * channels.size());
    for (std::size_t i = 0; i < data.size(); ++i)
      data[i] = constant ? *constant : static_cast<float>(std::sin(0.1 * i));
  }
  void send(int k, bool with_torque = true) {
    const VibrationBlockView block{51200.0, channels.data(), channels.size(), data.data(),
                                   data.size()};
    const Stamp stamp = test::stampAt(10.0 + k * 1024 / 51200.0);
    ASSERT_EQ(pipeline.vibration(stamp, block, sink), InputOutcome::kAccepted) << k;
    if (with_torque) {
      ASSERT_EQ(pipeline.torque(stamp, 0.5, sink), InputOutcome::kAccepted) << k;
    }
  }
  RigPipeline pipeline;
  PipelineSink sink;
  std::vector<std::string> channels;
  std::vector<float> data;  ///< sin(0.1 i), or the constant
};

// Vibration blocks (two channels and an unknown one, 1024 samples at 51.2 kHz) appended to the
// record past its length (4 s: the ring wraps), between torque inputs: none may allocate.
TEST(NoAllocation, VibrationBlocksInSteadyState) {
  VibrationFeed feed({"pinion_bearing", "tacho", "gear_bearing"}, PipelineOptions{});
  // 5 s: the record full, its ring wrapped, its first identification (4 s of blocks, 200) run
  // and applied 0.5 s later (block 225). An identification allocates (its record's copy, SSI's
  // matrices), once per record; the blocks between identifications allocate nothing.
  for (int k = 0; k < 250; ++k) feed.send(k);
  EXPECT_EQ(feed.pipeline.counters().modal_out + feed.pipeline.counters().modal_errors, 1u);
  const long before = allocationCount();
  for (int k = 250; k < 399; ++k) feed.send(k);  // block 399 completes the next record
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 149.0 << " heap allocations per block and torque input";
  EXPECT_EQ(feed.pipeline.counters().vibration.samples, 399u * 1024u);
}

// A lost block at the same rate starts a new record: the input's ring and the stage's two record
// buffers are kept (same size), so the restart allocates nothing.
TEST(NoAllocation, VibrationRecordRestartAfterAGap) {
  VibrationFeed feed({"pinion_bearing", "gear_bearing"}, PipelineOptions{});
  for (int k = 0; k < 50; ++k) feed.send(k);  // the first record: its buffers allocated
  const long before = allocationCount();
  for (int k = 51; k < 100; ++k) feed.send(k);  // block 50 lost: a gap, a new record
  const long n = allocationCount() - before;
  EXPECT_EQ(feed.pipeline.counters().vibration.gaps, 1u);
  EXPECT_EQ(n, 0) << n << " heap allocations over a record's restart";
  EXPECT_EQ(feed.pipeline.vibrationInput().appended(), 49u * 1024u);
}

TEST(NoAllocation, VibrationBlocksWithoutIdentification) {
  PipelineOptions options;
  options.modal_identification = false;
  VibrationFeed feed({"pinion_bearing", "gear_bearing"}, options, 0.5f);
  for (int k = 0; k < 250; ++k) feed.send(k, false);
  const long before = allocationCount();
  for (int k = 250; k < 500; ++k) feed.send(k, false);
  EXPECT_EQ(allocationCount() - before, 0);
}

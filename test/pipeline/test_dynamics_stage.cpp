// DynamicsStage: samples on their exact stamps reach every consumer in the order they were added,
// a torque input restarts a stopped model, the gap rule stops the model and restarts the
// consumers, each advance says what it did, and the TE output hands each sample its context.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "drivetrain_stiffness/pipeline/dynamics_stage.hpp"
#include "drivetrain_stiffness/pipeline/te_output.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

Stamp at(double seconds) { return test::stampAt(seconds); }

/// Logs what reaches it, tagged with its name.
struct Logger : SampleConsumer {
  Logger(std::string n, std::vector<std::string>& l) : name(std::move(n)), log(l) {}
  std::string name;
  std::vector<std::string>& log;
  std::vector<Stamp> stamps;
  int restarts = 0;
  void sample(Stamp stamp, const DynamicsSample& s, double, PipelineSink&) override {
    EXPECT_EQ(s.t, stamp.toSec());
    stamps.push_back(stamp);
    log.push_back(name);
  }
  void restart() override { ++restarts; }
};

struct Fixture {
  std::shared_ptr<const RigConfig> rig = std::make_shared<RigConfig>(test::seedServo());
  StiffnessEstimator estimator{rig};
  PipelineOptions options;
  DynamicsStage stage{rig, estimator, options, Fidelity::kFull};
  const DynamicsCounters& counters = stage.counters();
  std::vector<std::string> log;
  Logger a{"a", log}, b{"b", log};
  PipelineSink sink;
  Fixture() {
    stage.addConsumer(a);
    stage.addConsumer(b);
  }
};

}  // namespace

TEST(DynamicsStage, SamplesReachEveryConsumerInOrderOnExactStamps) {
  Fixture f;
  EXPECT_EQ(f.stage.advanceTo(at(1.0), f.sink), Advance::kStopped);
  EXPECT_EQ(f.stage.takeTorque(at(1.0), 0.1), TorqueTaken::kRestarted);
  EXPECT_EQ(f.a.restarts, 1);
  EXPECT_EQ(f.stage.advanceTo(at(1.0105), f.sink), Advance::kAdvanced);
  EXPECT_EQ(f.stage.takeTorque(at(1.0105), 0.1), TorqueTaken::kHeld);
  ASSERT_EQ(f.a.stamps.size(), 10u);  // 1 ms grid from the restart: 1.001 ... 1.010
  for (std::size_t k = 0; k < f.a.stamps.size(); ++k) {
    EXPECT_TRUE(f.a.stamps[k] == at(1.0 + 1e-3 * (k + 1)));
    EXPECT_TRUE(f.b.stamps[k] == f.a.stamps[k]);
    EXPECT_EQ(f.log[2 * k], "a");
    EXPECT_EQ(f.log[2 * k + 1], "b");
  }
  // At the nominal phase the state sits on the last sample before the input: that much was
  // integrated.
  EXPECT_NEAR(f.counters.simulated_s, 0.010, 1e-12);
  // Already past a stamp: nothing to do.
  EXPECT_EQ(f.stage.advanceTo(at(1.005), f.sink), Advance::kAlreadyPast);
}

TEST(DynamicsStage, TheGapRuleStopsTheModelAndRestartsTheConsumers) {
  Fixture f;
  f.stage.takeTorque(at(1.0), 0.1);
  f.stage.advanceTo(at(1.002), f.sink);
  const int restarts = f.b.restarts;
  // More than ~max_gap (1 s) on: not integrated.
  EXPECT_EQ(f.stage.advanceTo(at(2.5), f.sink), Advance::kGap);
  f.stage.stopAfterGap(at(2.5));
  EXPECT_EQ(f.counters.gap_restarts, 1u);
  EXPECT_FALSE(f.stage.dynamics().started());
  EXPECT_EQ(f.b.restarts, restarts + 1);
  EXPECT_EQ(f.stage.advanceTo(at(2.5), f.sink), Advance::kStopped);
  // The next torque input restarts it there.
  EXPECT_EQ(f.stage.takeTorque(at(2.5), 0.2), TorqueTaken::kRestarted);
  EXPECT_TRUE(f.stage.dynamics().started());
  EXPECT_FALSE(f.stage.momentAtOrAfter(at(2.5))->stamp < at(2.5));
  EXPECT_EQ(f.a.stamps.size(), 2u);  // nothing integrated across the gap
}

TEST(DynamicsStage, AMomentIsNeverBeforeTheModelsTime) {
  Fixture f;
  EXPECT_FALSE(f.stage.momentAtOrAfter(at(1.0)).has_value());  // stopped: no clock
  f.stage.takeTorque(at(1.0), 0.1);
  f.stage.advanceTo(at(1.0105), f.sink);  // nominal phase: the state sits on 1.010
  const auto behind = f.stage.momentAtOrAfter(at(1.004));
  ASSERT_TRUE(behind);
  EXPECT_NEAR(behind->t, 0.010, 1e-12);  // the model's time, on its own clock
  EXPECT_TRUE(behind->stamp == at(1.010));
  const auto ahead = f.stage.momentAtOrAfter(at(1.0107));
  EXPECT_NEAR(ahead->t, 0.0107, 1e-12);
  EXPECT_TRUE(ahead->stamp == at(1.0107));
}

TEST(DynamicsStage, AResetStopsUntilTheNextTorque) {
  Fixture f;
  f.stage.takeTorque(at(1.0), 0.1);
  f.stage.reset();
  EXPECT_FALSE(f.stage.dynamics().started());
  EXPECT_EQ(f.stage.advanceTo(at(1.01), f.sink), Advance::kStopped);
  EXPECT_TRUE(f.a.stamps.empty());
  EXPECT_EQ(f.stage.takeTorque(at(1.02), 0.1), TorqueTaken::kRestarted);
}

TEST(TeOutput, EachSampleCarriesTheEncoderAngleAndTheLastResonance) {
  PipelineOptions options;
  options.mesh_phase_offset = 0.5;
  PhaseSource phase{options, 20, 40};
  bool continuous = false;
  phase.anchorTo(phase.unwrap(at(0.0), MotionInput{0.2, 10.0, std::nullopt}, continuous));
  std::optional<ResonanceEstimate> resonance;
  TeOutput out(phase, resonance);
  struct Seen : PipelineSink {
    SampleContext context;
    void transmissionError(Stamp, const DynamicsSample&, const SampleContext& c) override {
      context = c;
    }
  } sink;
  out.sample(at(0.01), DynamicsSample{}, 0.0, sink);
  EXPECT_NEAR(sink.context.pinion_angle, 0.2 + 0.1, 1e-12);  // the encoder's angle, no offset
  EXPECT_EQ(sink.context.resonance, nullptr);
  resonance = ResonanceEstimate{};
  out.sample(at(0.02), DynamicsSample{}, 0.0, sink);
  EXPECT_EQ(sink.context.resonance, &*resonance);
  EXPECT_EQ(out.counters().te_out, 2u);
}

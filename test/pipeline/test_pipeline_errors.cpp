// What the pipeline catches: the library's own errors (drivetrain_stiffness::Error) are counted
// with their reason and the pipeline goes on; a programming error (std::logic_error,
// std::out_of_range, ...) is not caught, so a test that hits one fails instead of seeing a
// dynamics error in the counters. The errors are injected through a sink, whose callbacks run
// inside the pipeline's guarded sections (the TE samples inside the advance, the resonance inside
// its update).
#include <gtest/gtest.h>

#include <functional>
#include <stdexcept>
#include <type_traits>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() { return test::seedServo(); }
Stamp at(double seconds) { return test::stampAt(seconds); }

// Runs `on_sample` at the n-th TE sample (1-based) and `on_resonance` at every resonance.
struct InjectingSink : PipelineSink {
  int samples = 0, throw_at = -1;
  std::function<void()> on_sample, on_resonance, on_stiffness;
  void stiffness(Stamp, const StiffnessEstimate&, const CalibrationBands&) override {
    if (on_stiffness) on_stiffness();
  }
  void transmissionError(Stamp, const DynamicsSample&, const SampleContext&) override {
    if (++samples == throw_at && on_sample) on_sample();
  }
  void resonance(Stamp, const ResonanceEstimate&, const CalibrationBands&) override {
    if (on_resonance) on_resonance();
  }
};

}  // namespace

// The exceptions the library throws on purpose share one base, and none of them is a logic_error
// (which the pipeline leaves to surface).
static_assert(std::is_base_of_v<Error, InvalidInput> && std::is_base_of_v<Error, UnreachableLoad> &&
              std::is_base_of_v<Error, UnstableIntegration>);
static_assert(!std::is_base_of_v<std::logic_error, Error>);

TEST(PipelineErrors, TheLibrarysOwnErrorInTheDynamicsIsCountedAndTheModelRestarts) {
  RigPipeline p(rig(), PipelineOptions{});
  InjectingSink sink;
  sink.throw_at = 5;
  sink.on_sample = [] { throw UnstableIntegration("injected divergence"); };
  ASSERT_EQ(p.torque(at(0.0), 0.1, sink), InputOutcome::kAccepted);
  // 10 ms at the 1 kHz grid: the 5th sample throws; the input is still accepted (its stiffness is
  // good), the dynamics restart at it, counted once with the reason.
  EXPECT_EQ(p.torque(at(0.010), 0.1, sink), InputOutcome::kAccepted);
  EXPECT_EQ(p.counters().dynamics_errors, 1u);
  EXPECT_NE(p.counters().last_event.find("injected divergence"), std::string::npos)
      << p.counters().last_event;
  EXPECT_TRUE(p.dynamics()->started());
  // And it goes on: the next 10 ms give their samples.
  const int before = sink.samples;
  EXPECT_EQ(p.torque(at(0.020), 0.1, sink), InputOutcome::kAccepted);
  EXPECT_GE(sink.samples - before, 9);
  EXPECT_EQ(p.counters().dynamics_errors, 1u);
}

TEST(PipelineErrors, ALogicErrorInsideTheAdvanceSurfaces) {
  RigPipeline p(rig(), PipelineOptions{});
  InjectingSink sink;
  sink.throw_at = 5;
  sink.on_sample = [] { throw std::logic_error("a bug"); };
  ASSERT_EQ(p.torque(at(0.0), 0.1, sink), InputOutcome::kAccepted);
  EXPECT_THROW(p.torque(at(0.010), 0.1, sink), std::logic_error);
  EXPECT_EQ(p.counters().dynamics_errors, 0u);  // not mistaken for a dynamics failure
}

TEST(PipelineErrors, AnOutOfRangeInsideTheResonanceUpdateSurfaces) {
  RigPipeline p(rig(), PipelineOptions{});
  InjectingSink sink;
  sink.on_resonance = [] {
    const std::vector<int> none;
    (void)none.at(3);  // a bad index: std::out_of_range
  };
  EXPECT_THROW(p.torque(at(0.0), 0.1, sink), std::out_of_range);
  EXPECT_EQ(p.counters().dynamics_errors, 0u);
}

TEST(PipelineErrors, TheLibrarysOwnErrorInTheResonanceIsCounted) {
  RigPipeline p(rig(), PipelineOptions{});
  InjectingSink sink;
  sink.on_resonance = [] { throw InvalidInput("resonance: injected refusal"); };
  EXPECT_EQ(p.torque(at(0.0), 0.1, sink), InputOutcome::kAccepted);
  EXPECT_EQ(p.counters().dynamics_errors, 1u);
  EXPECT_NE(p.counters().last_event.find("injected refusal"), std::string::npos)
      << p.counters().last_event;
}

// A stiffness message the sink refuses (the ROS sink refuses a non-finite field, InvalidInput):
// the input was taken (its stiffness is in the estimator and reaches the dynamics), so it is
// counted accepted once and not also rejected, and the refusal has a count of its own.
TEST(PipelineErrors, ARefusedStiffnessMessageLeavesTheInputAcceptedOnce) {
  RigPipeline p(rig(),
                PipelineOptions{});  // stiffness_rate 0 (RuntimeSettings): a message per input
  ASSERT_EQ(p.settings().stiffness_rate, 0.0);
  InjectingSink sink;
  int refusals = 0;
  sink.on_stiffness = [&] {
    if (++refusals <= 2) throw InvalidInput("stiffness.mesh_mean = nan: not finite, not published");
  };
  ASSERT_EQ(p.torque(at(0.0), 0.1, sink), InputOutcome::kAccepted);
  ASSERT_EQ(p.torque(at(0.010), 0.2, sink), InputOutcome::kAccepted);
  EXPECT_EQ(p.counters().accepted_torque, 2u);
  EXPECT_EQ(p.counters().rejected_torque, 0u);
  EXPECT_EQ(p.counters().invalid_values, 0u);
  EXPECT_EQ(p.counters().stiffness_refused, 2u);
  EXPECT_EQ(p.counters().stiffness_out, 0u);
  EXPECT_NE(p.counters().last_event.find("not published"), std::string::npos)
      << p.counters().last_event;
  // The input's stiffness went on to the dynamics and the resonance (pushStiffness, after the
  // refused message): the first input's modal analysis was run and published.
  EXPECT_GE(p.counters().modal_updates, 1u);
  EXPECT_GE(p.counters().resonance_out, 1u);
  // The dynamics ran over the refused inputs (10 samples at the 1 kHz grid), and the third input's
  // message is published.
  EXPECT_GE(sink.samples, 9);
  ASSERT_EQ(p.torque(at(0.020), 0.2, sink), InputOutcome::kAccepted);
  EXPECT_EQ(p.counters().stiffness_out, 1u);
  EXPECT_EQ(p.counters().stiffness_refused, 2u);
}

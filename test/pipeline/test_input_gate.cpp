// InputGate: each time, frame and value rule by its name, on each stream's own stamps; a refusal
// counted by stream and reason with its tally entry; drops counted from header.seq; the clock-jump
// rule, and a source restart that came first taking its place once.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/pipeline/input_gate.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

Stamp at(double seconds) { return test::stampAt(seconds); }

struct Fixture {
  PipelineOptions options = [] {
    PipelineOptions o;
    o.stamp_jump_back = 1.0;
    o.clock_jump_back = 1.0;
    o.torque_frame = "rig";
    return o;
  }();
  InputGate gate{options};
  const GateCounters& counters = gate.counters();
};

}  // namespace

TEST(InputGate, TheStampRulesByName) {
  Fixture f;
  EXPECT_TRUE(InputGate::isZeroStamp(Stamp{0}));
  EXPECT_FALSE(InputGate::isZeroStamp(at(0.0)));
  EXPECT_TRUE(InputGate::outsideRosTime(Stamp{-1}));
  EXPECT_TRUE(InputGate::outsideRosTime(Stamp{Stamp::kMaxRosNs + 1}));
  EXPECT_FALSE(InputGate::outsideRosTime(Stamp{Stamp::kMaxRosNs}));
  const std::optional<Stamp> last = at(10.0);
  EXPECT_FALSE(f.gate.isOutOfOrder(at(10.0), last));  // a burst: equal stamps are in order
  EXPECT_TRUE(f.gate.isOutOfOrder(at(9.5), last));
  EXPECT_TRUE(f.gate.isOutOfOrder(at(9.0), last));  // back by exactly ~stamp_jump_back
  EXPECT_FALSE(f.gate.sourceRestarted(at(9.0), last));
  EXPECT_FALSE(f.gate.isOutOfOrder(at(8.5), last));
  EXPECT_TRUE(f.gate.sourceRestarted(at(8.5), last));
  EXPECT_FALSE(f.gate.isOutOfOrder(at(8.5), std::nullopt));
  EXPECT_FALSE(f.gate.sourceRestarted(at(8.5), std::nullopt));
}

TEST(InputGate, TheFrameRuleIgnoresALeadingSlash) {
  Fixture f;
  EXPECT_FALSE(f.gate.isWrongFrame("rig"));
  EXPECT_FALSE(f.gate.isWrongFrame("/rig"));
  EXPECT_TRUE(f.gate.isWrongFrame("base_link"));
  EXPECT_TRUE(f.gate.isWrongFrame(""));
  EXPECT_EQ(f.gate.checkFrame(at(1.0), InputOrigin{"pub", 0, "base_link"}),
            InputOutcome::kWrongFrame);
  EXPECT_EQ(f.counters.wrong_frames, 1u);
  EXPECT_EQ(f.counters.rejected_torque, 1u);
  EXPECT_EQ(
      f.gate.refusals().entry(InputStream::kTorque, InputOutcome::kWrongFrame).found.at(0).value,
      "base_link");
  PipelineOptions any;
  EXPECT_FALSE(InputGate(any).isWrongFrame("anything"));
}

TEST(InputGate, EachStreamKeepsItsOwnStamps) {
  Fixture f;
  EXPECT_EQ(f.gate.checkStamp(InputStream::kTorque, Stamp{0}), InputOutcome::kZeroStamp);
  EXPECT_EQ(f.gate.checkStamp(InputStream::kTorque, Stamp{-5}), InputOutcome::kStampRange);
  f.gate.accept(InputStream::kTorque, at(10.0));
  EXPECT_EQ(f.counters.accepted_torque, 1u);
  EXPECT_EQ(f.gate.checkStamp(InputStream::kTorque, at(9.5)), InputOutcome::kOutOfOrder);
  EXPECT_EQ(f.gate.checkStamp(InputStream::kPreload, at(9.5)), InputOutcome::kAccepted);
  EXPECT_FALSE(f.gate.noteSourceRestart(InputStream::kTorque, at(9.5)));
  const std::optional<std::string> restart =
      f.gate.noteSourceRestart(InputStream::kTorque, at(5.0));
  ASSERT_TRUE(restart);
  EXPECT_NE(restart->find("torque stamp went back by 5"), std::string::npos) << *restart;
  EXPECT_EQ(f.counters.stamp_resets, 1u);
  f.gate.forgetStamps();
  EXPECT_EQ(f.gate.checkStamp(InputStream::kTorque, at(5.0)), InputOutcome::kAccepted);
}

TEST(InputGate, ARefusalIsCountedByStreamAndReasonWithWhy) {
  Fixture f;
  EXPECT_EQ(f.gate.reject(InputOutcome::kInvalidValue, InputStream::kJointStates, at(1.0),
                          "no pinion joint", "a,b"),
            InputOutcome::kInvalidValue);
  EXPECT_EQ(f.counters.rejected_motion, 1u);
  EXPECT_EQ(f.counters.invalid_values, 1u);
  EXPECT_EQ(f.gate.events().last(), "joint_states rejected (invalid value): no pinion joint");
  const RefusalTally::Entry& e =
      f.gate.refusals().entry(InputStream::kJointStates, InputOutcome::kInvalidValue);
  EXPECT_EQ(e.count, 1u);
  EXPECT_EQ(e.first_reason, "no pinion joint");
  f.gate.reject(InputOutcome::kOutOfOrder, InputStream::kPreload, at(1.0), "late");
  EXPECT_EQ(f.counters.rejected_preload, 1u);
  EXPECT_EQ(f.counters.out_of_order, 1u);
}

TEST(InputGate, DropsAreCountedFromTheSequenceNumbers) {
  Fixture f;
  for (std::uint32_t seq : {1u, 2u, 5u})
    f.gate.countDrops(InputStream::kPreload, InputOrigin{"pub", seq, ""});
  EXPECT_EQ(f.counters.dropped_preload, 2u);
  EXPECT_EQ(f.counters.dropped_torque, 0u);
  f.gate.countDrops(InputStream::kTorque, InputOrigin{"quiet", 0, ""});
  f.gate.countDrops(InputStream::kTorque, InputOrigin{"quiet", 0, ""});
  EXPECT_EQ(f.gate.unnumberedPublishers(), 1u);
}

TEST(InputGate, TheClockJumpRuleAndASourceRestartThatCameFirst) {
  Fixture f;
  EXPECT_FALSE(f.gate.observeClock(at(100.0)));
  EXPECT_FALSE(f.gate.observeClock(at(99.5)));  // a correction within ~clock_jump_back
  EXPECT_TRUE(f.gate.clockJumpedBack(at(50.0)));
  EXPECT_TRUE(f.gate.observeClock(at(50.0)));
  EXPECT_EQ(f.counters.clock_resets, 1u);
  // The loop's stamps restarted first: its clock jump is the same restart, skipped once.
  f.gate.accept(InputStream::kTorque, at(60.0));
  ASSERT_TRUE(f.gate.noteSourceRestart(InputStream::kTorque, at(10.0)));
  EXPECT_FALSE(f.gate.observeClock(at(10.0)));
  EXPECT_TRUE(f.gate.observeClock(at(1.0)));
  EXPECT_EQ(f.counters.clock_resets, 2u);
}

TEST(InputGate, TheReadingsValueRules) {
  EXPECT_THROW(InputGate::validateReading(MotionInput{std::nan(""), std::nullopt, std::nullopt}),
               InvalidInput);
  EXPECT_THROW(InputGate::validateReading(MotionInput{0.0, 2e4, std::nullopt}),
               InvalidInput);  // beyond 1e5 rpm
  EXPECT_THROW(InputGate::validateReading(MotionInput{0.0, 10.0, INFINITY}), InvalidInput);
  EXPECT_NO_THROW(InputGate::validateReading(MotionInput{1e9, -1e4, 3.0}));
}

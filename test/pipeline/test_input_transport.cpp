// Transport rules of the pipeline: messages lost on the way are counted from the publishers'
// header.seq (SequenceGaps), a torque in another frame is refused, stamps ros::Time cannot hold are
// refused, and a backlogged input is shed (dynamics at its stamp, no stiffness update) with the
// transmission error exactly as if it had not been shed.
#include <gtest/gtest.h>

#include <cmath>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "drivetrain_stiffness/pipeline/sequence_gaps.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() { return test::seedServo(); }

constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;  // 2026-01-01
Stamp at(double seconds) { return Stamp{kEpoch + std::llround(seconds * 1e9)}; }

struct Counting : PipelineSink {
  int stiffness_out = 0;
  std::vector<std::pair<Stamp, double>> te;  // stamp, dynamic TE
  void stiffness(Stamp, const StiffnessEstimate&, const CalibrationBands&) override {
    ++stiffness_out;
  }
  void transmissionError(Stamp stamp, const DynamicsSample& s, const SampleContext&) override {
    ASSERT_TRUE(std::isfinite(s.dynamic_te));
    te.emplace_back(stamp, s.dynamic_te);
  }
};

}  // namespace

TEST(SequenceGaps, CountsWhatANumberingPublisherLost) {
  SequenceGaps gaps;
  EXPECT_EQ(gaps.observe("/rig", 10), 0u);  // first message: nothing known before it
  EXPECT_EQ(gaps.observe("/rig", 11), 0u);
  EXPECT_EQ(gaps.observe("/rig", 15), 3u);   // 12, 13, 14 never arrived
  EXPECT_EQ(gaps.observe("/other", 0), 0u);  // another publisher numbers on its own
  EXPECT_EQ(gaps.observe("/other", 2), 1u);
  EXPECT_EQ(gaps.observe("/rig", 16), 0u);
  EXPECT_EQ(gaps.unnumberedPublishers(), 0u);
}

TEST(SequenceGaps, WrapsRestartsAndUnnumberedPublishers) {
  SequenceGaps gaps;
  gaps.observe("/rig", 0xFFFFFFFEu);
  EXPECT_EQ(gaps.observe("/rig", 0xFFFFFFFFu), 0u);
  EXPECT_EQ(gaps.observe("/rig", 1u), 1u);  // wrapped through 0: message 0 lost
  EXPECT_EQ(gaps.observe("/rig", 0u), 0u);  // numbers went back: the publisher restarted
  EXPECT_EQ(gaps.renumberings(), 1u);
  EXPECT_EQ(gaps.observe("/rig", 1u), 0u);
  // A publisher whose header.seq stays constant (a zero-copy nodelet publication that does not set
  // it): nothing can be seen, and it is said so.
  for (int i = 0; i < 5; ++i) EXPECT_EQ(gaps.observe("/cpp_driver", 0u), 0u);
  EXPECT_EQ(gaps.unnumberedPublishers(), 1u);
}

TEST(SequenceGaps, PublisherTableIsBounded) {
  SequenceGaps gaps;
  for (std::size_t i = 0; i < SequenceGaps::kMaxPublishers + 10; ++i)
    gaps.observe("/p" + std::to_string(i), 0);
  EXPECT_EQ(gaps.untracked(), 10u);
}

TEST(RigPipeline, DroppedInputsAreCountedPerStream) {
  PipelineOptions o;
  o.dynamics = false;
  RigPipeline p(rig(), o);
  Counting sink;
  std::uint32_t seq = 0;
  for (int k = 0; k < 100; ++k) {
    if (k == 40) seq += 7;  // 7 lost in the transport
    p.torque(at(1e-3 * k), 0.1, sink, {"/rig", seq++, "pinion"});
  }
  p.preload(at(0.1), {{"pinion_bearing", 500.0, 1000.0, 0.0, 0.0}}, sink, {"/preload_ctl", 4, ""});
  p.preload(at(0.2), {{"pinion_bearing", 600.0, 1000.0, 0.0, 0.0}}, sink, {"/preload_ctl", 6, ""});
  EXPECT_EQ(p.counters().dropped_torque, 7u);
  EXPECT_EQ(p.counters().dropped_preload, 1u);
  EXPECT_EQ(p.counters().accepted_torque, 100u);  // the held torque is simply the last one received
}

TEST(RigPipeline, TorqueInAnotherFrameIsRefused) {
  PipelineOptions o;
  o.dynamics = false;
  o.torque_frame = "pinion";
  RigPipeline p(rig(), o);
  Counting sink;
  EXPECT_EQ(p.torque(at(0.0), 0.1, sink, {"/rig", 0, "pinion"}), InputOutcome::kAccepted);
  EXPECT_EQ(p.torque(at(0.001), 0.1, sink, {"/rig", 1, "/pinion"}),
            InputOutcome::kAccepted);  // tf2 strips the '/'
  EXPECT_EQ(p.torque(at(0.002), -0.1, sink, {"/rig", 2, "gear"}), InputOutcome::kWrongFrame);
  EXPECT_EQ(p.torque(at(0.003), 0.1, sink, {"/rig", 3, ""}), InputOutcome::kWrongFrame);
  EXPECT_EQ(p.counters().wrong_frames, 2u);
  EXPECT_EQ(p.counters().rejected_torque, 2u);
  EXPECT_NE(p.counters().last_event.find("header.frame_id = ''"), std::string::npos)
      << p.counters().last_event;
  EXPECT_EQ(sink.stiffness_out, 2);
  o.torque_frame = "/pinion";
  EXPECT_THROW(RigPipeline(rig(), o), InvalidInput);
}

TEST(RigPipeline, StampsOutsideRosTimeAreRefused) {
  PipelineOptions o;
  o.dynamics = false;
  RigPipeline p(rig(), o);
  Counting sink;
  EXPECT_EQ(p.torque(Stamp{-5}, 0.1, sink), InputOutcome::kStampRange);
  EXPECT_EQ(p.torque(Stamp{Stamp::kMaxRosNs + 1}, 0.1, sink), InputOutcome::kStampRange);
  EXPECT_EQ(p.torque(Stamp{Stamp::kMaxRosNs}, 0.1, sink),
            InputOutcome::kAccepted);  // 2106-02-07T06:28:15.999999999
  EXPECT_EQ(p.counters().stamps_out_of_range, 2u);
}

// Shedding skips the stiffness update and message of a backlogged input but integrates the
// dynamics with its torque at its stamp: the transmission error equals the unshed run's sample for
// sample while the bearing stiffness stays within the 1 % at which the dynamics rebuild.
TEST(RigPipeline, ShedInputsKeepTheTransmissionErrorAndAreCounted) {
  PipelineOptions o;
  o.limits.load_tolerance = 0.0;
  RigPipeline exact(rig(), o), shedding(rig(), o);
  Counting a, b;
  for (int k = 0; k < 2000; ++k) {
    const double torque = 0.1 * (1.0 + 0.05 * std::sin(0.03 * k));  // a slow 5 % ripple
    exact.torque(at(1e-4 * k), torque, a, {"/rig", static_cast<std::uint32_t>(k), ""});
    // Inputs 200-1799: a backlog; all but every 50th is shed.
    const Backlog backlog = k >= 200 && k < 1800 && k % 50 != 0 ? Backlog::kShed : Backlog::kNone;
    shedding.torque(at(1e-4 * k), torque, b, {"/rig", static_cast<std::uint32_t>(k), ""}, backlog);
  }
  const PipelineCounters& c = shedding.counters();
  EXPECT_EQ(c.accepted_torque, 2000u);
  EXPECT_EQ(c.stiffness_shed, 1600u - 32u);
  EXPECT_EQ(static_cast<std::uint64_t>(b.stiffness_out) + c.stiffness_shed, c.accepted_torque);
  ASSERT_EQ(a.te.size(), b.te.size());
  ASSERT_GT(a.te.size(), 100u);
  for (std::size_t i = 0; i < a.te.size(); ++i) {
    EXPECT_EQ(a.te[i].first, b.te[i].first);
    EXPECT_EQ(a.te[i].second, b.te[i].second) << "sample " << i;
  }
  // The newest input after the backlog brings the stiffness estimate back to the exact one.
  EXPECT_EQ(shedding.estimator().current().torque, exact.estimator().current().torque);
}

// The vibration input through RigPipeline: each block rule with its counter and refusal, the
// channel map (support names, aliases with a sign, unknown names counted and ignored), and the
// record kept continuous across blocks, restarted at a gap, a rate change or other channels.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

Stamp at(double seconds) { return test::stampAt(seconds); }

PipelineOptions noDynamics() {
  PipelineOptions o;
  o.dynamics = false;
  return o;
}

/// A block of `frames` samples per channel whose value at (frame i, channel c) is
/// first + i + 1000 c, so each kept value names where it came from.
struct Block {
  double rate = 51200.0;
  std::vector<std::string> channels{"pinion_bearing", "gear_bearing"};
  std::vector<float> data;
  Block(std::size_t frames, double first = 0.0) { fill(frames, first); }
  void fill(std::size_t frames, double first) {
    data.resize(frames * channels.size());
    for (std::size_t i = 0; i < frames; ++i) {
      for (std::size_t c = 0; c < channels.size(); ++c) {
        data[i * channels.size() + c] = static_cast<float>(first + i + 1000.0 * c);
      }
    }
  }
  VibrationBlockView view() const {
    return {rate, channels.data(), channels.size(), data.data(), data.size()};
  }
  double seconds() const { return data.size() / channels.size() / rate; }
};

struct Rig {
  RigPipeline pipeline;
  PipelineSink sink;
  explicit Rig(const PipelineOptions& options = noDynamics())
      : pipeline(test::seedServo(), options) {}
  InputOutcome send(double t, const Block& b, std::uint32_t seq = 0) {
    return pipeline.vibration(at(t), b.view(), sink, {"/daq", seq, ""});
  }
  const PipelineCounters& counters() const { return pipeline.counters(); }
  const VibrationInput& record() const { return pipeline.vibrationInput(); }
  std::string lastReason() const {
    return pipeline.refusals()
        .entry(InputStream::kVibration, InputOutcome::kInvalidValue)
        .first_reason;
  }
};

}  // namespace

TEST(VibrationChannels, SupportsByNameThenAliasesWithTheirSign) {
  const RigConfig& rig = test::seedServo();
  const auto map = vibrationChannels(rig, {{"acc_3", "gear_bearing", -1.0}});
  ASSERT_EQ(map.size(), 3u);
  EXPECT_EQ(map[0].name, "pinion_bearing");  // seed gearbox: bearings[0] on the pinion shaft
  EXPECT_EQ(map[0].shaft, 0);
  EXPECT_EQ(map[1].name, "gear_bearing");
  EXPECT_EQ(map[1].shaft, 1);
  EXPECT_EQ(map[2].shaft, 1);
  EXPECT_EQ(map[2].sign, -1.0);
}

TEST(VibrationChannels, RefusesAnUnknownSupportABadSignAndARepeatedName) {
  const RigConfig& rig = test::seedServo();
  try {
    vibrationChannels(rig, {{"acc_3", "housing", 1.0}});
    FAIL() << "accepted an unknown support";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("vibration_channels[acc_3].support = 'housing'"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("pinion_bearing, gear_bearing"), std::string::npos);
  }
  EXPECT_THROW(vibrationChannels(rig, {{"acc_3", "gear_bearing", 0.5}}), InvalidInput);
  EXPECT_THROW(vibrationChannels(rig, {{"pinion_bearing", "gear_bearing", 1.0}}), InvalidInput);
  EXPECT_THROW(vibrationChannels(rig, {{"", "gear_bearing", 1.0}}), InvalidInput);
  PipelineOptions options = noDynamics();
  options.vibration_channels = {{"acc_3", "housing", 1.0}};
  EXPECT_THROW(RigPipeline(test::seedServo(), options), InvalidInput);
}

TEST(VibrationInput, ConsecutiveBlocksMakeOneRecord) {
  Rig r;
  Block b(512);
  double t = 10.0;
  for (int k = 0; k < 4; ++k) {
    b.fill(512, 512.0 * k);
    EXPECT_EQ(r.send(t, b), InputOutcome::kAccepted);
    t += b.seconds();
  }
  EXPECT_EQ(r.counters().accepted_vibration, 4u);
  EXPECT_EQ(r.counters().vibration.samples, 2048u);
  ASSERT_EQ(r.record().frames(), 2048u);
  ASSERT_EQ(r.record().columns(), 2u);
  for (std::size_t i = 0; i < 2048; i += 97) {
    EXPECT_EQ(r.record().value(0, i), static_cast<float>(i));
    EXPECT_EQ(r.record().value(1, i), static_cast<float>(i + 1000.0));
  }
  EXPECT_EQ(r.record().origin(), at(10.0));
  EXPECT_EQ(r.record().frameTime(51200), 1.0);
  EXPECT_EQ(r.counters().vibration.gaps + r.counters().vibration.overlaps, 0u);
}

TEST(VibrationInput, StampJitterAndClockDriftWithinHalfABlockKeepTheRecord) {
  // Unnumbered blocks of 1024 samples at 51.2 kHz (20 ms): stamps jittered by +-3 ms around a
  // clock 100 ppm fast against the converter's, for 100 s. Each block is judged against the one
  // before, so the drift (10 ms over the run, half a block) never adds up.
  Rig r;
  Block b(1024);
  const double block = b.seconds();
  for (int k = 0; k < 5000; ++k) {
    const double jitter = (k % 7 - 3) * 1e-3;
    ASSERT_EQ(r.send(10.0 + k * block * (1.0 + 1e-4) + jitter, b), InputOutcome::kAccepted) << k;
  }
  EXPECT_EQ(r.counters().vibration.gaps, 0u);
  EXPECT_EQ(r.counters().vibration.overlaps, 0u);
  EXPECT_EQ(r.counters().vibration.samples, 5000u * 1024u);
  // The record keeps vibration_record = 4 s of the newest samples.
  EXPECT_EQ(r.record().frames(), static_cast<std::size_t>(4.0 * 51200));
}

TEST(VibrationInput, ALostBlockIsAGapAndStartsANewRecord) {
  Rig r;
  Block b(1024);
  r.send(10.0, b);
  r.send(10.0 + b.seconds(), b);
  b.fill(1024, 7.0);
  EXPECT_EQ(r.send(10.0 + 3 * b.seconds(), b), InputOutcome::kAccepted);  // one block missing
  EXPECT_EQ(r.counters().vibration.gaps, 1u);
  EXPECT_EQ(r.record().frames(), 1024u);
  EXPECT_EQ(r.record().value(0, 0), 7.0f);
  EXPECT_EQ(r.record().origin(), at(10.0 + 3 * b.seconds()));
}

TEST(VibrationInput, AnOverlappingBlockIsRefusedAndCounted) {
  Rig r;
  Block b(1024);
  r.send(10.0, b);
  EXPECT_EQ(r.send(10.0 + 0.4 * b.seconds(), b), InputOutcome::kInvalidValue);
  EXPECT_EQ(r.counters().vibration.overlaps, 1u);
  EXPECT_EQ(r.counters().rejected_vibration, 1u);
  EXPECT_NE(r.lastReason().find(
                "overlaps the previous block (header.seq = 0), starting 0.012 s before its end"),
            std::string::npos)
      << r.lastReason();
  EXPECT_EQ(r.record().frames(), 1024u);  // nothing of the refused block kept
  // After a refusal the next block starts a new record: the refused samples are missing.
  EXPECT_EQ(r.send(10.0 + b.seconds(), b), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.gaps, 1u);
  EXPECT_EQ(r.record().frames(), 1024u);
  EXPECT_EQ(r.record().origin(), at(10.0 + b.seconds()));
}

TEST(VibrationInput, ExactlyHalfABlockEarlyIsAnOverlap) {
  Rig r;
  Block b(1024);
  r.send(10.0, b);
  EXPECT_EQ(r.send(10.0 + 0.5 * b.seconds(), b), InputOutcome::kInvalidValue);
  EXPECT_EQ(r.counters().vibration.overlaps, 1u);
}

TEST(VibrationInput, NumberedShortBlocksFollowTheirNumbersThroughStampJitter) {
  // 256 samples at 102.4 kHz (2.5 ms blocks) stamped with +-1 ms of jitter: consecutive stamps
  // differ by 0.5 to 4.5 ms, more than half a block off, so only header.seq tells a late block from
  // a lost one.
  Rig r;
  Block b(256);
  b.rate = 102400.0;
  b.fill(256, 0.0);
  const double block = b.seconds();
  std::uint32_t seq = 1;
  for (int k = 0; k < 400; ++k, ++seq) {
    const double jitter = (k % 5 - 2) * 0.5e-3;
    ASSERT_EQ(r.send(10.0 + k * block + jitter, b, seq), InputOutcome::kAccepted) << k;
  }
  EXPECT_EQ(r.counters().vibration.gaps, 0u);
  EXPECT_EQ(r.record().frames(), 400u * 256u);
  // Block 401 lost: 402 starts a new record; 402 again is an overlap.
  EXPECT_EQ(r.send(10.0 + 401 * block, b, seq + 1), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.gaps, 1u);
  EXPECT_EQ(r.counters().dropped_vibration, 1u);
  EXPECT_EQ(r.record().frames(), 256u);
  EXPECT_EQ(r.send(10.0 + 401 * block, b, seq + 1), InputOutcome::kInvalidValue);
  EXPECT_EQ(r.counters().vibration.overlaps, 1u);
  // The block after a refusal starts a new record.
  EXPECT_EQ(r.send(10.0 + 402 * block, b, seq + 2), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.gaps, 2u);
  // Numbers that continue over a pause in the stamps (acquisition stopped and went on): a gap.
  EXPECT_EQ(r.send(12.0, b, seq + 3), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.gaps, 3u);
  EXPECT_EQ(r.record().frames(), 256u);
}

TEST(VibrationInput, AMeasuredRateThatWandersByLessThanAPpmKeepsTheRecord) {
  Rig r;
  Block b(1024);
  r.send(10.0, b);
  b.rate = 51200.0 * (1.0 + 5e-7);
  EXPECT_EQ(r.send(10.0 + 1024 / 51200.0, b), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.rate_changes, 0u);
  EXPECT_EQ(r.record().frames(), 2048u);
  b.rate = 51200.0 * (1.0 + 2e-6);
  r.send(10.0 + 2048 / 51200.0, b);
  EXPECT_EQ(r.counters().vibration.rate_changes, 1u);
}

TEST(VibrationInput, ARecordBeyondTheMemoryBudgetIsRefusedNamingTheRate) {
  // 4 s at 10 MHz on two mapped channels: 4e7 frames x 2 x 4 bytes = 305 MiB > 256 MiB.
  Rig r;
  Block b(64);
  b.rate = 1e7;
  EXPECT_EQ(r.send(10.0, b), InputOutcome::kInvalidValue);
  EXPECT_NE(r.lastReason().find("vibration: sample_rate = 10000000"), std::string::npos)
      << r.lastReason();
  EXPECT_NE(r.lastReason().find("305.1757812 MiB, more than 256 MiB"), std::string::npos)
      << r.lastReason();
  EXPECT_FALSE(r.record().recording());
}

TEST(VibrationInput, ARateChangeOrOtherChannelsStartANewRecord) {
  Rig r;
  Block b(1024);
  r.send(10.0, b);
  Block faster(2048);
  faster.rate = 102400.0;
  EXPECT_EQ(r.send(10.0 + b.seconds(), faster), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.rate_changes, 1u);
  EXPECT_EQ(r.record().sampleRate(), 102400.0);
  EXPECT_EQ(r.record().frames(), 2048u);
  Block swapped(2048);
  swapped.rate = 102400.0;
  swapped.channels = {"gear_bearing", "pinion_bearing"};
  swapped.fill(2048, 0.0);
  EXPECT_EQ(r.send(10.0 + b.seconds() + faster.seconds(), swapped), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.channel_changes, 1u);
  EXPECT_EQ(r.record().column(0).name, "gear_bearing");
  EXPECT_EQ(r.record().value(0, 5), 5.0f);
}

TEST(VibrationInput, UnknownChannelsAreCountedAndIgnoredAliasesTakeTheirSign) {
  PipelineOptions options = noDynamics();
  options.vibration_channels = {{"acc_z", "gear_bearing", -1.0}};
  Rig r(options);
  Block b(100);
  b.channels = {"tacho", "pinion_bearing", "acc_z", "mic"};
  b.fill(100, 0.0);
  EXPECT_EQ(r.send(10.0, b), InputOutcome::kAccepted);
  EXPECT_EQ(r.counters().vibration.unknown_channels, 2u);
  ASSERT_EQ(r.record().columns(), 2u);
  EXPECT_EQ(r.record().column(0).shaft, 0);
  EXPECT_EQ(r.record().value(0, 3), 1003.0f);  // pinion_bearing is channel 1
  EXPECT_EQ(r.record().column(1).shaft, 1);
  EXPECT_EQ(r.record().value(1, 3), -2003.0f);  // acc_z is channel 2, sign -1
  EXPECT_EQ(r.record().unknownNames(), (std::vector<std::string>{"tacho", "mic"}));
}

TEST(VibrationInput, TheValueRulesNameTheField) {
  Rig r;
  Block b(8);
  b.data[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(r.send(10.0, b), InputOutcome::kInvalidValue);
  EXPECT_NE(r.lastReason().find("vibration: data[5] (channel 'gear_bearing', sample 2) = nan"),
            std::string::npos)
      << r.lastReason();
  Block odd(8);
  odd.data.pop_back();
  EXPECT_EQ(r.send(11.0, odd), InputOutcome::kInvalidValue);
  Block rate(8);
  rate.rate = 0.0;
  EXPECT_EQ(r.send(12.0, rate), InputOutcome::kInvalidValue);
  Block none(8);
  none.channels = {"tacho", "mic"};
  EXPECT_EQ(r.send(13.0, none), InputOutcome::kInvalidValue);
  Block twice(8);
  twice.channels = {"gear_bearing", "gear_bearing"};
  EXPECT_EQ(r.send(14.0, twice), InputOutcome::kInvalidValue);
  Block huge(8);
  huge.data[0] = 2e6f;
  EXPECT_EQ(r.send(15.0, huge), InputOutcome::kInvalidValue);
  EXPECT_EQ(r.counters().rejected_vibration, 6u);
  EXPECT_EQ(r.counters().invalid_values, 6u);
  EXPECT_EQ(r.counters().accepted_vibration, 0u);
  EXPECT_FALSE(r.record().recording());
}

TEST(VibrationInput, TheTimeRulesAndASourceRestartApply) {
  Rig r;
  Block b(1024);
  EXPECT_EQ(r.pipeline.vibration(Stamp{0}, b.view(), r.sink), InputOutcome::kZeroStamp);
  r.send(100.0, b);
  EXPECT_EQ(r.send(99.5, b), InputOutcome::kOutOfOrder);  // back by less than ~stamp_jump_back
  EXPECT_EQ(r.send(50.0, b), InputOutcome::kAccepted);    // back by more: the source restarted
  EXPECT_EQ(r.counters().stamp_resets, 1u);
  EXPECT_EQ(r.record().frames(), 1024u);
  EXPECT_EQ(r.record().origin(), at(50.0));
  EXPECT_EQ(r.counters().vibration.overlaps, 0u);
}

TEST(VibrationInput, DropsAreCountedFromTheHeaderSequence) {
  Rig r;
  Block b(1024);
  r.pipeline.vibration(at(10.0), b.view(), r.sink, {"/daq", 1, ""});
  r.pipeline.vibration(at(10.0 + b.seconds()), b.view(), r.sink, {"/daq", 4, ""});
  EXPECT_EQ(r.counters().dropped_vibration, 2u);
}

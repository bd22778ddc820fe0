// The fuzz targets in ctest: every seed file, then 1000 seeded mutations per target (fixed seed, so
// the same cases on every run and compiler). Bounded by case count, never by time. The verdict:
// no finding (no crash, no escaped exception type, every refusal names its field, no non-finite
// output), and the cases reach both sides of the checks (some inputs accepted, some refused).
#include <gtest/gtest.h>

#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz_driver.hpp"
#include "fuzz_target.hpp"

using namespace drivetrain_stiffness::fuzz;

namespace {

constexpr std::uint64_t kCases = 1000;
constexpr std::uint64_t kSeed = 20260101;

class FuzzTargetTest : public testing::TestWithParam<std::string> {};

TEST_P(FuzzTargetTest, SeededCasesFindNothing) {
  const FuzzTarget* target = findFuzzTarget(GetParam());
  ASSERT_NE(target, nullptr);
  RunOptions options;
  options.cases = kCases;
  options.seed = kSeed;
  const RunStats stats = runTarget(*target, options);
  EXPECT_EQ(stats.cases, stats.corpus_cases + kCases);
  for (const Finding& f : stats.findings) {
    ADD_FAILURE() << target->name << " case " << f.case_number << ": " << f.what
                  << "\n  input: " << hexDump(f.input);
  }
  EXPECT_GT(stats.accepted, 0u) << "no input accepted: the cases never get past the checks";
  EXPECT_GT(stats.refused, 0u) << "no input refused: the cases never exercise the checks";
  std::printf("%s: %llu cases (%llu seeds), %llu inputs accepted, %llu refused, %zu findings\n",
              target->name, static_cast<unsigned long long>(stats.cases),
              static_cast<unsigned long long>(stats.corpus_cases),
              static_cast<unsigned long long>(stats.accepted),
              static_cast<unsigned long long>(stats.refused), stats.findings.size());
}

// The seed corpus is what its file names say: each valid_* seed is accepted whole (no input of
// it refused), each invalid_* one refused. (regress_* seeds are fuzz findings, kept as seeds.)
TEST_P(FuzzTargetTest, SeedsAreWhatTheirNamesSay) {
  const FuzzTarget* target = findFuzzTarget(GetParam());
  ASSERT_NE(target, nullptr);
  const std::vector<SeedFile> seeds = loadCorpusFiles(*target);
  ASSERT_FALSE(seeds.empty());
  for (const SeedFile& seed : seeds) {
    const CaseStats c = target->fuzzOne(seed.bytes.data(), seed.bytes.size());
    if (seed.name.rfind("valid_", 0) == 0) {
      EXPECT_GT(c.accepted, 0u) << seed.name;
      EXPECT_EQ(c.refused, 0u) << seed.name
                               << (c.refusals.empty() ? "" : ": " + c.refusals.front());
    } else if (seed.name.rfind("invalid_", 0) == 0) {
      EXPECT_GT(c.refused, 0u) << seed.name;
    }
  }
}

std::uint64_t counter(const CaseStats& c, const std::string& name) {
  for (const auto& [key, value] : c.counters) {
    if (key == name) return value;
  }
  ADD_FAILURE() << "no counter " << name;
  return 0;
}

const SeedFile& seedNamed(const std::vector<SeedFile>& seeds, const std::string& name) {
  for (const SeedFile& s : seeds) {
    if (s.name == name) return s;
  }
  throw std::runtime_error("no seed " + name);
}

// The vibration seeds count what docs/vibration.md "Input" says their blocks break (the blocks
// are listed in test/fuzz/make_pipeline_seeds.py).
TEST(PipelineVibrationSeeds, CountWhatTheRulesSay) {
  const FuzzTarget* target = findFuzzTarget("pipeline");
  ASSERT_NE(target, nullptr);
  const std::vector<SeedFile> seeds = loadCorpusFiles(*target);
  auto run = [&](const std::string& name) {
    const SeedFile& s = seedNamed(seeds, name);
    return target->fuzzOne(s.bytes.data(), s.bytes.size());
  };
  // 4 blocks at 51.2 kHz, then 9 of 32 frames at 64 Hz: a new rate (a new record), filled after 8
  // (4 s = 256 frames), so one identification ends, with a report or an error.
  const CaseStats valid = run("valid_vibration.bin");
  EXPECT_EQ(counter(valid, "accepted_vibration"), 13u);
  EXPECT_EQ(counter(valid, "vibration_samples"), 13u * 32u);
  EXPECT_EQ(counter(valid, "vibration_rate_changes"), 1u);
  EXPECT_EQ(counter(valid, "vibration_gaps"), 0u);
  EXPECT_EQ(counter(valid, "modal_identifications_published") +
                counter(valid, "modal_identification_errors"),
            1u);
  // 10 broken blocks between 2 good ones, each refused by a value rule, nothing of them kept.
  const CaseStats values = run("invalid_vibration_values.bin");
  EXPECT_EQ(counter(values, "accepted_vibration"), 2u);
  EXPECT_EQ(counter(values, "rejected_vibration"), 10u);
  EXPECT_EQ(counter(values, "vibration_samples"), 64u);
  for (const char* field : {"data[5]", "data[7]", "data.size() = 63", "data.size() = 0",
                            "sample_rate = 0", "sample_rate = -51200", "channels.size() = 0",
                            "channels[0] is empty", "none names a bearing support", "repeats"}) {
    bool named = false;
    for (const std::string& r : values.refusals)
      named = named || r.find(field) != std::string::npos;
    EXPECT_TRUE(named) << field;
  }
  // Rates: within the tolerance continues, past it and 25.6 kHz restart (2); a skipped number, a
  // block after a refused one and an unnumbered one after numbered ones are gaps (3); the same
  // number again and an unnumbered block 0.95 ms early overlap (2, refused); an unknown extra
  // channel and then one channel fewer change the channels (2), the unknown one counted once.
  const CaseStats continuity = run("invalid_vibration_continuity.bin");
  EXPECT_EQ(counter(continuity, "accepted_vibration"), 9u);
  EXPECT_EQ(counter(continuity, "rejected_vibration"), 2u);
  EXPECT_EQ(counter(continuity, "vibration_rate_changes"), 2u);
  EXPECT_EQ(counter(continuity, "vibration_gaps"), 3u);
  EXPECT_EQ(counter(continuity, "vibration_overlaps"), 2u);
  EXPECT_EQ(counter(continuity, "vibration_channel_changes"), 2u);
  EXPECT_EQ(counter(continuity, "vibration_unknown_channels"), 1u);
  EXPECT_EQ(counter(continuity, "vibration_samples"), 9u * 32u);
}

std::vector<std::string> targetNames() {
  std::vector<std::string> names;
  for (const FuzzTarget& t : fuzzTargets()) names.push_back(t.name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzTargetTest, testing::ValuesIn(targetNames()),
                         [](const testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace

// The fuzz targets in ctest: every seed file, then 1000 seeded mutations per target (fixed seed, so
// the same cases on every run and compiler). Bounded by case count, never by time. The verdict:
// no finding (no crash, no escaped exception type, every refusal names its field, no non-finite
// output), and the cases reach both sides of the checks (some inputs accepted, some refused).
#include <gtest/gtest.h>

#include <cstdio>

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

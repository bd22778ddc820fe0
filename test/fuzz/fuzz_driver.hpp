// Runs a target over its seed corpus and then over seeded mutations of it (mutator.hpp): what the
// ctest (fixed case count) and the long run (drivetrain_fuzz) share. Deterministic for a seed: the
// n-th case is the same on every run, so a finding is reproduced by its seed and case number, or
// by the case file written to findings_dir.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "fuzz_target.hpp"
#include "mutator.hpp"

namespace drivetrain_stiffness::fuzz {

struct RunOptions {
  std::uint64_t cases = 1000;  ///< mutated cases, run after every corpus file once as it is
  std::uint64_t seed = 1;
  /// > 0: a watchdog ends the process (exit 124) when one case runs longer. For the long run only:
  /// no ctest verdict may depend on the machine's speed, so ctest bounds cases by count.
  double case_timeout_s = 0.0;
  /// Non-empty: each finding's case is written there, and the running case to last-<target>.bin
  /// (left behind if the process dies in it: a crash, a sanitizer report, the watchdog).
  std::string findings_dir;
  bool collect_refusals = false;  ///< count refusal messages by shape (numbers masked), for review
};

struct Finding {
  std::uint64_t case_number;  ///< 0-based; corpus files first
  std::string what;
  Bytes input;
};

struct RunStats {
  std::uint64_t cases = 0, corpus_cases = 0;
  std::uint64_t accepted = 0, refused = 0;  ///< inputs (a pipeline case holds many)
  std::vector<Finding> findings;
  double slowest_case_s = 0.0;  ///< reported, never asserted
  std::uint64_t slowest_case = 0;
  std::map<std::string, std::uint64_t> refusal_shapes;
};

struct SeedFile {
  std::string name;  ///< file name, e.g. valid_seed_servo.yaml
  Bytes bytes;
};
/// The target's seed files (test/data/fuzz/<corpus>/), in name order.
std::vector<SeedFile> loadCorpusFiles(const FuzzTarget& target);
/// The corpus as it is, then options.cases mutated cases.
RunStats runTarget(const FuzzTarget& target, const RunOptions& options);
/// Keys of the schema and node parameter names: the mutator's dictionary for text targets.
std::vector<std::string> fuzzDictionary();
/// "6b 65 79 3a ..." for a report.
std::string hexDump(const Bytes& bytes, std::size_t max_bytes = 256);

}  // namespace drivetrain_stiffness::fuzz

// The fuzz targets: one `fuzzOne(data, size)` per input surface (the YAML loaders, the node's
// parameters, the pipeline's message inputs), driven alike by libFuzzer (libfuzzer_main.cpp), by
// the seeded mutator in ctest (test_fuzz.cpp) and by the long run (drivetrain_fuzz.cpp).
//
// A target returns normally when the library either accepted the input or refused it the
// documented way (InvalidInput / UnreachableLoad naming the field); it throws FuzzFinding when a
// property is violated (another exception type escaped, a refusal does not name its field, a
// non-finite value was handed out). A crash or a sanitizer report is a finding too, by itself.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace drivetrain_stiffness::fuzz {

/// A violated property. Never caught by a target; the drivers report it with the case bytes.
class FuzzFinding : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

/// What one case did: counts of inputs accepted and refused (a YAML case is one input; a pipeline
/// case is a sequence of messages), and the refusal messages (for review: --show-refusals).
struct CaseStats {
  std::uint64_t accepted = 0, refused = 0;
  std::vector<std::string> refusals;
  /// The library's own counters at the case's end, by name (the pipeline target's namedCounters).
  std::vector<std::pair<std::string, std::uint64_t>> counters;
  void refuse(const std::string& message) {
    ++refused;
    refusals.push_back(message);
  }
};

struct FuzzTarget {
  const char* name;
  const char* corpus;  ///< directory under test/data/fuzz/ with the seed inputs
  bool text;           ///< YAML text (the mutator edits lines and tokens) or a binary program
  CaseStats (*fuzzOne)(const std::uint8_t* data, std::size_t size);
  std::size_t max_size;  ///< mutated cases are cut to this many bytes
};

CaseStats fuzzBearingFile(const std::uint8_t* data, std::size_t size);
CaseStats fuzzGearFile(const std::uint8_t* data, std::size_t size);
CaseStats fuzzRigFile(const std::uint8_t* data, std::size_t size);
CaseStats fuzzNodeParameters(const std::uint8_t* data, std::size_t size);
CaseStats fuzzPipeline(const std::uint8_t* data, std::size_t size);
/// drivetrain_replay's bag reader on a bag file's bytes (ReplayInput).
CaseStats fuzzBag(const std::uint8_t* data, std::size_t size);

const std::vector<FuzzTarget>& fuzzTargets();
/// nullptr if there is no target of that name.
const FuzzTarget* findFuzzTarget(const std::string& name);

/// The source tree (for the seed corpus and the bearing files a gearbox file references).
std::string sourceDir();

}  // namespace drivetrain_stiffness::fuzz

// libFuzzer entry for one target, chosen at build time (DRIVETRAIN_FUZZ_TARGET, one binary per
// target: cmake/fuzz_tests.cmake). A finding aborts, which libFuzzer reports as a crash and saves.
#include <cstdio>
#include <cstdlib>

#include "fuzz_target.hpp"

using namespace drivetrain_stiffness::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const FuzzTarget* target = findFuzzTarget(DRIVETRAIN_FUZZ_TARGET);
  if (!target) {
    std::fprintf(stderr, "no fuzz target %s\n", DRIVETRAIN_FUZZ_TARGET);
    std::abort();
  }
  try {
    target->fuzzOne(data, size);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "FINDING in %s: %s\n", target->name, e.what());
    std::abort();
  }
  return 0;
}

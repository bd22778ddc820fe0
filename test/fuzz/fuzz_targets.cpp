#include "fuzz_target.hpp"

namespace drivetrain_stiffness::fuzz {

const std::vector<FuzzTarget>& fuzzTargets() {
  static const std::vector<FuzzTarget> targets = {
      // Text: room for the mutator's deep nesting (3000 brackets); a pipeline program: more than
      // kMaxOperations operations; a bag: the seed bags (test/fuzz/make_bag_seeds.py) and growth.
      {"bearing_yaml", "bearing", true, &fuzzBearingFile, 8192},
      {"gear_yaml", "gear", true, &fuzzGearFile, 8192},
      {"rig_yaml", "rig", true, &fuzzRigFile, 8192},
      {"node_params", "node_params", true, &fuzzNodeParameters, 8192},
      {"pipeline", "pipeline", false, &fuzzPipeline, 1024},
      {"bag", "bag", false, &fuzzBag, 32768},
  };
  return targets;
}

const FuzzTarget* findFuzzTarget(const std::string& name) {
  for (const FuzzTarget& t : fuzzTargets()) {
    if (name == t.name) return &t;
  }
  return nullptr;
}

std::string sourceDir() { return DRIVETRAIN_SOURCE_DIR; }

}  // namespace drivetrain_stiffness::fuzz

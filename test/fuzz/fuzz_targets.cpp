#include "fuzz_target.hpp"

namespace drivetrain_stiffness::fuzz {

const std::vector<FuzzTarget>& fuzzTargets() {
  static const std::vector<FuzzTarget> targets = {
      {"bearing_yaml", "bearing", true, &fuzzBearingFile},
      {"gear_yaml", "gear", true, &fuzzGearFile},
      {"rig_yaml", "rig", true, &fuzzRigFile},
      {"node_params", "node_params", true, &fuzzNodeParameters},
      {"pipeline", "pipeline", false, &fuzzPipeline},
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

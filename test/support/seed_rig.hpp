// The seed gearbox (config/gearboxes/seed_servo.yaml, seed 000 Table 1) and stamps on a fixed
// epoch, as the pipeline tests feed them. Header-only, for the test binaries.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace drivetrain_stiffness::test {

/// The seed gearbox, loaded once.
inline const RigConfig& seedServo() {
  static const RigConfig r =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  return r;
}

/// 2026-01-01T00:00:00Z [ns]: the test stamps' epoch.
constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;
/// The stamp `seconds` after kEpoch.
inline Stamp stampAt(double seconds) { return Stamp{kEpoch + std::llround(seconds * 1e9)}; }

}  // namespace drivetrain_stiffness::test

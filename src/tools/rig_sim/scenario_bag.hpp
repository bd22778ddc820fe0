// A scenario's events written to a bag as the rig publishes them, reproducible byte for byte.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "scenarios/rig_scenarios.hpp"  // NOLINT(build/include_subdir)
#include "rig_vibration.hpp"            // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {

struct ScenarioBagOptions {
  double epoch = 1767225600.0;  ///< [s] the scenario's start (stamps and record times)
  std::string torque_topic = "/torque";
  std::string preload_topic = "/preload";
  std::string joint_topic = "/joint_states";
  std::string pinion_joint = "pinion";  ///< JointState.name[0]
  std::string gear_joint = "gear";      ///< JointState.name[1]
  std::string vibration_topic = "/vibration";
};

struct ScenarioBagCounts {
  std::size_t torque = 0, preload = 0, joint_states = 0, vibration = 0;
};

/// Writes `events` in their order to a new bag at `path` (overwritten), and the blocks of
/// `vibration` (none if null) each at the record time its last sample completes it, before the
/// events of a later record time. Throws InvalidInput for an epoch outside [1, 4e9) s or empty
/// topic or joint names.
ScenarioBagCounts writeScenarioBag(const std::vector<RigEvent>& events,
                                   const ScenarioBagOptions& options, const std::string& path,
                                   const VibrationRecord* vibration = nullptr);

}  // namespace drivetrain_stiffness

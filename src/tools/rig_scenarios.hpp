// Documented rig input scenarios (README, "drivetrain_rig_sim"), as plain timed events:
// what drivetrain_rig_sim writes to bags and the tests feed to the pipeline. ROS-free.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

namespace drivetrain_stiffness {

struct RigEvent {
  double t = 0.0;                       ///< [s] since the scenario start (stamp = epoch + t)
  std::optional<double> torque;         ///< [N*m] pinion torque input
  std::vector<PreloadSetting> preload;  ///< preload input (empty: none)
  bool zero_stamp = false;              ///< fault injection: publish with a stamp of 0
  double stamp_offset = 0.0;            ///< [s] fault injection: stamp = epoch + t + offset
  std::uint32_t lost_before = 0;        ///< fault injection: messages of its stream lost before it (seq gap)
  std::string frame_id = "pinion";      ///< torque frame (fault injection: another one)
};

struct ScenarioSpec {
  std::string name;
  double duration = 2.0;      ///< [s]
  double torque_rate = 1000;  ///< [Hz] torque samples
};

/// Names: torque_ripple, torque_steps, preload_ramp, speed_sweep, faults (see scenarioHelp()).
std::vector<RigEvent> makeScenario(const RigConfig& rig, const ScenarioSpec& spec);
std::string scenarioHelp();

}  // namespace drivetrain_stiffness

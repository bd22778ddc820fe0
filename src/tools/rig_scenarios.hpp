// Documented rig input scenarios (README, "drivetrain_rig_sim"), as plain timed events:
// what drivetrain_rig_sim writes to bags and the tests feed to the pipeline. ROS-free.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/motion.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

namespace drivetrain_stiffness {

struct RigEvent {
  double t = 0.0;                       ///< [s] since the scenario start (stamp = epoch + t)
  std::optional<double> torque;         ///< [N*m] pinion torque input
  std::vector<PreloadSetting> preload;  ///< preload input (empty: none)
  bool zero_stamp = false;              ///< fault injection: publish with a stamp of 0
  double stamp_offset = 0.0;            ///< [s] fault injection: stamp = epoch + t + offset
  std::uint32_t lost_before =
      0;  ///< fault injection: messages of its stream lost before it (seq gap)
  std::string frame_id = "pinion";  ///< torque frame (fault injection: another one)
  /// Encoder reading of both shafts (joint_states), in events of its own: angles quantised to the
  /// 2^20-count grid, the pinion's exact speed unless ScenarioSpec::joint_velocity is false.
  /// (= std::nullopt: the aggregate initialisations that leave it out stay -Wextra clean.)
  std::optional<MotionInput> motion = std::nullopt;
  std::optional<double> gear_velocity =
      std::nullopt;  ///< [rad/s] beside motion->pinion_velocity (JointState.velocity[1])
};

struct ScenarioSpec {
  std::string name;
  double duration = 2.0;      ///< [s]
  double torque_rate = 1000;  ///< [Hz] torque samples
  double joint_rate = 1000;   ///< [Hz] encoder readings (motion events); 0: none
  bool joint_velocity =
      true;  ///< false: the readings carry no velocity (the node differentiates the angle)
};

/// Names: torque_ripple, torque_steps, preload_ramp, speed_sweep, faults (at the gearbox's constant
/// dynamics.speed_rpm), run_up, coast_down, speed_steps, reverse (see scenarioHelp()). load_sweep,
/// which needs a seed and a speed, is makeLoadSweep (load_sweep.hpp): here it is refused.
std::vector<RigEvent> makeScenario(const RigConfig& rig, const ScenarioSpec& spec);
std::string scenarioHelp();

}  // namespace drivetrain_stiffness

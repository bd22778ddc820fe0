// The documented rig input scenarios as timed events (docs/tools.md "drivetrain_rig_sim").
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/dynamics/motion.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/dynamics/speed_profile.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

namespace drivetrain_stiffness {

struct RigEvent {
  double t = 0.0;                       ///< [s] since the start (stamp = epoch + t)
  std::optional<double> torque;         ///< [N*m]
  std::vector<PreloadSetting> preload;  ///< empty: none
  bool zero_stamp = false;              ///< fault: a stamp of 0
  double stamp_offset = 0.0;            ///< [s] fault: stamp = epoch + t + offset
  std::uint32_t lost_before = 0;        ///< fault: a seq gap before it
  std::string frame_id = "pinion";
  std::optional<MotionInput> motion = std::nullopt;    ///< an encoder reading (rig_encoder.hpp)
  std::optional<double> gear_velocity = std::nullopt;  ///< [rad/s]
};

struct ScenarioSpec {
  std::string name;
  double duration = 2.0;      ///< [s]
  double torque_rate = 1000;  ///< [Hz]
  double joint_rate = 1000;   ///< [Hz]; 0: no readings
  bool joint_velocity = true;
};

/// The named scenario's events in send order (scenarioHelp()). Throws InvalidInput naming the
/// field, or the scenario for an unknown name or load_sweep (makeLoadSweep).
std::vector<RigEvent> makeScenario(const RigConfig& rig, const ScenarioSpec& spec);
std::string scenarioHelp();
/// The pinion speed of the named scenario (not load_sweep): the speed scenarios' profiles, else the
/// gearbox's constant dynamics.speed_rpm (1000 rpm without a dynamics block). Throws InvalidInput
/// naming the field.
SpeedProfile scenarioSpeedProfile(const RigConfig& rig, const ScenarioSpec& spec);

}  // namespace drivetrain_stiffness

// Which shaft coordinate each accelerometer channel measures (docs/vibration.md "Input"). ROS-free.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace drivetrain_stiffness {

struct RigConfig;

/// `name` measures the transverse acceleration of shaft `shaft` (0 pinion: x_p, 1 gear: x_g, seed
/// 000 §3) along the line of action, times `sign` (+1 or -1).
struct VibrationChannel {
  std::string name;
  int shaft = 0;
  double sign = 1.0;
};

/// A ~vibration_channels entry: channel `name` measures the support named `support` (a
/// bearings[].name of the gearbox), times `sign`.
struct VibrationChannelAlias {
  std::string name, support;
  double sign = 1.0;
};

/// The aliases of a ~vibration_channels map, channel name -> support name, with a leading '-' where
/// the sensor's axis points against the line of action ({acc_z: "-gear_bearing"}).
std::vector<VibrationChannelAlias> parseVibrationAliases(
    const std::map<std::string, std::string>& entries);

/// Channel names to shafts: every bearing support's own name (sign +1), then the aliases.
/// Throws InvalidInput naming an alias with an unknown support, an empty or repeated name, or a
/// sign other than +-1.
std::vector<VibrationChannel> vibrationChannels(const RigConfig& rig,
                                                const std::vector<VibrationChannelAlias>& aliases);

}  // namespace drivetrain_stiffness

// YAML configuration shared by drivetrain_cli, the ROS node and the replay tool, so that one
// parser and one set of checks define what a valid rig is. Every key is SI (m, N, Pa) except the
// angles, whose keys say _deg. Unknown keys are errors (a typo must not silently fall back to a
// default), and every error names the file, the key and the value.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "drivetrain_stiffness/core/bearing_support.hpp"
#include "drivetrain_stiffness/core/gear_geometry.hpp"

namespace drivetrain_stiffness {

/// One bearing support of the rig with its operating settings (the `preload` topic updates them).
struct BearingSupportConfig {
  std::string name;                        ///< e.g. "pinion_bearing"
  BallBearingSpec spec;
  Arrangement arrangement = Arrangement::kSingle;
  TiltCondition tilt = TiltCondition::kConstrained;
  double axial_preload = 0.0;              ///< [N]
  double radial_preload = 0.0;             ///< external radial load besides the mesh force [N]
  Interference interference;               ///< diametral [m]
  int shaft = 0;                           ///< 0 pinion, 1 gear
  double mesh_load_share = 1.0;            ///< fraction of the mesh force this support reacts
};

struct RigConfig {
  GearPairSpec gears;
  std::vector<BearingSupportConfig> bearings;
};

/// Parses a `bearing:` mapping (keys in the README); `where` prefixes error messages.
BearingSupportConfig parseBearing(const YAML::Node& node, const std::string& where);
/// Loads a file with a top-level `bearing:` block (config/bearings/*.yaml).
BearingSupportConfig loadBearingFile(const std::string& path);
/// Loads a gearbox file with `gears:` and `bearings:` (config/gearboxes/*.yaml). A bearing entry
/// may hold its keys inline or name a bearing file with `file:` (relative to the gearbox file).
RigConfig loadRigFile(const std::string& path);

}  // namespace drivetrain_stiffness

// YAML configuration shared by drivetrain_cli, the ROS node and the replay tool, so that one
// parser and one set of checks define what a valid rig is. Every key is SI (m, N, Pa) except the
// angles, whose keys say _deg. Unknown keys are errors (a typo must not silently fall back to a
// default), and every error names the file, the key and the value.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// The range [kScaleLowest, kScaleBound) the loader takes for every stiffness scale (the mesh's,
/// each bearing's, and their calibration priors' means); a prior's std is at most its width.
inline constexpr double kScaleLowest = 0.05, kScaleBound = 20.0;

/// Parses a `bearing:` mapping (keys in the README); `where` prefixes error messages.
BearingSupportConfig parseBearing(const YAML::Node& node, const std::string& where);
/// Loads a file with a top-level `bearing:` block (config/bearings/*.yaml).
BearingSupportConfig loadBearingFile(const std::string& path);
/// Parses a `gears:` mapping (and optional `anti_backlash:` / `mesh:` siblings of `root`).
void parseGears(const YAML::Node& root, const std::string& where, RigConfig& rig);
/// Loads a file with `gears:` (and optionally `anti_backlash:`, `mesh:`); `bearings:` is ignored.
RigConfig loadGearFile(const std::string& path);
/// Loads a gearbox file with `gears:` and `bearings:` (config/gearboxes/*.yaml). A bearing entry
/// may hold its keys inline or name a bearing file with `file:` (relative to the gearbox file).
RigConfig loadRigFile(const std::string& path);

}  // namespace drivetrain_stiffness

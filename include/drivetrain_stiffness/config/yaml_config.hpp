// The one YAML parser of rigs, bearings and gears: docs/configuration.md. Every error names the
// file, the key and the value (InvalidInput).
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// The range [kScaleLowest, kScaleBound) of every stiffness scale and prior mean.
inline constexpr double kScaleLowest = 0.05, kScaleBound = 20.0;

/// Parses a `bearing:` mapping; `where` prefixes error messages.
BearingSupportConfig parseBearing(const YAML::Node& node, const std::string& where);
/// Loads a file with a top-level `bearing:` block (config/bearings/*.yaml).
BearingSupportConfig loadBearingFile(const std::string& path);
/// Parses `gears:` and the optional `anti_backlash:` and `mesh:` of `root`.
void parseGears(const YAML::Node& root, const std::string& where, RigConfig& rig);
/// Loads a file's `gears:`, `anti_backlash:` and `mesh:`.
RigConfig loadGearFile(const std::string& path);
/// Loads a gearbox file (config/gearboxes/*.yaml); a bearing's `file:` is relative to it.
RigConfig loadRigFile(const std::string& path);

}  // namespace drivetrain_stiffness

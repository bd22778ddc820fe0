// drivetrain_replay --calibrate: the gearbox YAML with the live calibration's result, a file the
// node and the tools load like any other (loadRigFile). ROS-free.
//
// It starts from the --config file's YAML tree (yaml-cpp: its comments are not kept) and sets
//  - mesh.stiffness_scale                  = mesh_stiffness_scale
//  - bearings[i].stiffness_scale           = the scale of bearing i's shaft (pinion_bearing_scale
//  or
//                                            gear_bearing_scale)
//  - anti_backlash.preload_torque          = preload_torque (with a scissor spring only)
//  - calibration.<parameter>: {mean, std}  = the posterior (mean = estimate, std = posterior std)
// and keeps everything else. A bearing entry's relative `file:` resolves against the gearbox file's
// directory: when the output goes to another directory it is rewritten as an absolute path.
// A header comment says which bag, when, and which parameters the data did not identify.
#pragma once

#include <string>

#include "drivetrain_stiffness/calibration/calibrator.hpp"

namespace drivetrain_stiffness {

/// Where the calibration came from, for the header comment (free text, one line each).
struct CalibrationProvenance {
  std::string bag;       ///< the replayed bag
  std::string recorded;  ///< the record times it spans (e.g. "2026-01-01T00:00:00Z to
                         ///< 2026-01-01T00:00:02Z")
  std::string written;   ///< when the file was written (UTC)
  std::string status;    ///< the replay's status ("ok", or "incomplete: ...")
};

/// The calibrated gearbox YAML text for `config_path` (the file the replay ran with), to be written
/// at `out_path` (for the `file:` references). Refuses (InvalidInput naming --calibrate) a config
/// without a calibration block and an estimate that no window updated.
std::string calibratedGearboxYaml(const std::string& config_path,
                                  const CalibrationEstimate& estimate, const std::string& out_path,
                                  const CalibrationProvenance& provenance);

/// calibratedGearboxYaml written to `out_path` (its directory created if needed). Throws
/// InvalidInput as above, std::runtime_error naming the path if it cannot be written.
void writeCalibratedGearbox(const std::string& config_path, const CalibrationEstimate& estimate,
                            const std::string& out_path, const CalibrationProvenance& provenance);

/// A double as a YAML scalar that reads back exactly (shortest round-trip form) and that YAML 1.1
/// readers take as a number too: a '.' in the mantissa, a sign in the exponent ("1.0e-07").
std::string yamlNumber(double value);

}  // namespace drivetrain_stiffness

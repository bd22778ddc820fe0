// drivetrain_replay --calibrate: the gearbox YAML with the live calibration's result (docs/tools.md
// "drivetrain_replay", --calibrate).
#pragma once

#include <string>

#include "drivetrain_stiffness/calibration/calibrator.hpp"

namespace drivetrain_stiffness {

/// Where the calibration came from, for the file's header comment.
struct CalibrationProvenance {
  std::string bag;
  std::string recorded;  ///< the record times it spans
  std::string written;   ///< UTC
  std::string status;    ///< the replay's status
};

/// The calibrated gearbox YAML for `config_path`, to be written at `out_path`. Throws InvalidInput
/// naming --calibrate for a config without a calibration block or an estimate no window updated.
std::string calibratedGearboxYaml(const std::string& config_path,
                                  const CalibrationEstimate& estimate, const std::string& out_path,
                                  const CalibrationProvenance& provenance);

/// calibratedGearboxYaml written to `out_path`. Throws as it does, and std::runtime_error naming
/// the path if it cannot be written.
void writeCalibratedGearbox(const std::string& config_path, const CalibrationEstimate& estimate,
                            const std::string& out_path, const CalibrationProvenance& provenance);

/// The shortest YAML 1.1 number that reads back as `value` exactly ("1.0e-07").
std::string yamlNumber(double value);

}  // namespace drivetrain_stiffness

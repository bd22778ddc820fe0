// The parameter studies of seed 000 (sections 4.1-4.3, Figs 4, 5, 9, 10, 11) as tables: each study
// varies the bearing settings (interference, preloads) of BOTH supports together, as the seed
// does with its two equal bearings b1 and b2, and records the bearing radial stiffness, the
// natural frequencies at the mean composite mesh stiffness, or the RMS response of a torque sweep.
// ROS-free; no plotting here (scripts/plot_study.py draws the CSV).
#pragma once

#include <string>
#include <vector>

#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// One study's result: named columns (SI units in the names), one row per grid point.
struct StudyTable {
  std::string name;                  ///< e.g. "bearing_preload"
  std::string seed_figure;           ///< e.g. "seed 000 Fig 5"
  std::string kind;                  ///< "surface" (first two columns are the grid) or "curves"
  std::vector<std::string> columns;  ///< column names with units, e.g. "radial_preload_N"
  std::vector<std::vector<double>> rows;
};

/// The study names, in seed figure order.
const std::vector<std::string>& studyNames();

/// Runs the named study on `rig` (the seed's ranges; throws InvalidInput for an unknown name or a
/// rig without what the study needs, e.g. no dynamics block for the resonance studies).
StudyTable runStudy(const std::string& name, const RigConfig& rig);

/// Writes the table as CSV (header line, then rows; full double precision).
void writeStudyCsv(const StudyTable& table, const std::string& path);

}  // namespace drivetrain_stiffness

// The parameter studies of seed 000 (Figs 4, 5, 9, 10, 11) as tables: docs/resonance.md
// "Parameter studies".
#pragma once

#include <string>
#include <vector>

#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// One study's result: named columns (units in the names), one row per grid point.
struct StudyTable {
  std::string name;         ///< e.g. "bearing_preload"
  std::string seed_figure;  ///< e.g. "seed 000 Fig 5"
  std::string kind;         ///< "surface" (the first two columns are the grid) or "curves"
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};

/// The study names, in seed figure order.
const std::vector<std::string>& studyNames();

/// The named study on `rig` over the seed's ranges. Throws InvalidInput for an unknown name or a
/// rig without what the study needs.
StudyTable runStudy(const std::string& name, const RigConfig& rig);

/// Writes the table as CSV at full double precision.
void writeStudyCsv(const StudyTable& table, const std::string& path);

}  // namespace drivetrain_stiffness

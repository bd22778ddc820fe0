// Natural frequencies and Floquet stability of a rig at one operating point: docs/cli.md "modes".
#pragma once

#include <array>
#include <optional>

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// Smallest and largest composite mesh stiffness [N/m] over one mesh period.
struct MeshStiffnessRange {
  double min = 0.0, max = 0.0;
};

/// The extremes of the composite stiffness at phases (i + 0.5) / samples under the signed mesh
/// force [N]. Throws InvalidInput unless samples >= 1.
MeshStiffnessRange meshStiffnessRange(const AntiBacklashMesh& mesh, double mesh_force,
                                      int samples = 1024);

/// Floquet stability over one mesh period at the rig's nominal speed.
struct MeshPeriodFloquet {
  double mesh_frequency = 0.0;  ///< [Hz]
  FloquetResult result;
};

struct OperatingPointModes {
  double torque = 0.0;                                  ///< [N·m] pinion
  std::array<double, 2> bearing_stiffness{{0.0, 0.0}};  ///< [N/m] radial, per shaft
  GearRotorParameters parameters;
  double mesh_mean = 0.0;         ///< [N/m]
  MeshStiffnessRange mesh_range;  ///< [N/m] single pair (min), double pair (max)
  std::array<Mode, 3> modes_mean, modes_single_pair, modes_double_pair;
  std::optional<MeshPeriodFloquet> floquet;  ///< none with bearing clearance
};

/// The modes of `rig` at pinion torque [N·m]. Throws InvalidInput without a dynamics block or for a
/// non-finite torque.
OperatingPointModes operatingPointModes(const RigConfig& rig, double torque);

}  // namespace drivetrain_stiffness

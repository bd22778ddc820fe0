// Natural frequencies and Floquet stability of a configured rig at one operating point (pinion
// torque, the rig's nominal speed): the numbers of `drivetrain_cli modes` (docs/resonance.md).
//
//  - bearing stiffness per shaft: the bearing model at this torque (StiffnessEstimator, summed
//    over each shaft's supports);
//  - mesh stiffness: its period mean (meanMeshStiffness) and the extremes of the composite
//    stiffness over one mesh period at this torque's mesh force, which are the single- and
//    double-pair stiffness (the composite is constant within each contact zone);
//  - modes of the linearised 3-DOF model at each of the three (modal_analysis.hpp);
//  - Floquet multipliers over one mesh period of the model at the nominal speed (the exact product
//    of the exponential propagators; modal_analysis.hpp), unless a bearing has radial clearance
//    (no linear regime).
#pragma once

#include <array>
#include <optional>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// Smallest and largest composite mesh stiffness [N/m] over one mesh period.
struct MeshStiffnessRange {
  double min = 0.0, max = 0.0;
};

/// The composite stiffness at `samples` phases (i + 0.5) / samples of one mesh period, at the
/// signed mesh force [N] that sets the flank state; samples >= 1 (InvalidInput otherwise). A zone
/// shorter than a sample spacing can be missed: 1024 resolve the seed pair's zones (0.37 and 0.63
/// of the period) with room to spare.
MeshStiffnessRange meshStiffnessRange(const AntiBacklashMesh& mesh, double mesh_force,
                                      int samples = 1024);

/// Floquet stability over one mesh period at the rig's nominal speed.
struct MeshPeriodFloquet {
  double mesh_frequency = 0.0;  ///< z_p n / 60 [Hz]
  FloquetResult result;         ///< multipliers, max |mu| and margin 1 - max |mu|
};

struct OperatingPointModes {
  double torque = 0.0;                                  ///< pinion torque [N·m]
  std::array<double, 2> bearing_stiffness{{0.0, 0.0}};  ///< radial, per shaft (pinion, gear) [N/m]
  GearRotorParameters parameters;  ///< masses, radii, stiffness, damping of the model
  double mesh_mean = 0.0;          ///< period mean of the composite [N/m]
  MeshStiffnessRange mesh_range;   ///< single pair (min), double pair (max) [N/m]
  std::array<Mode, 3> modes_mean, modes_single_pair, modes_double_pair;
  std::optional<MeshPeriodFloquet> floquet;  ///< none with bearing clearance
};

/// The modes of `rig` (which needs a dynamics block: InvalidInput naming the file's block
/// otherwise) at pinion torque `torque` [N·m] (finite).
OperatingPointModes operatingPointModes(const RigConfig& rig, double torque);

}  // namespace drivetrain_stiffness

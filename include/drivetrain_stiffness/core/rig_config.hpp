// Plain description of a rig (gear pair and bearing supports with their operating settings),
// filled by the YAML loader and consumed by the estimator. No I/O here.
#pragma once

#include <string>
#include <vector>

#include "drivetrain_stiffness/core/bearing_support.hpp"
#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
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
  AntiBacklashSpec anti_backlash;          ///< spring_stiffness 0 = an ordinary (single) gear
  MeshStiffnessModel mesh_model = MeshStiffnessModel::kPotentialEnergy;
  int mesh_samples = 256;                  ///< table samples over the path of contact
  std::vector<BearingSupportConfig> bearings;
};

}  // namespace drivetrain_stiffness

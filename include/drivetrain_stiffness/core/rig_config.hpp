// Plain description of a rig (gear pair and bearing supports with their operating settings),
// filled by the YAML loader and consumed by the estimator. No I/O here.
#pragma once

#include <array>
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

/// The `dynamics:` block: what the 3-DOF model needs beyond the gears and bearings (SI units).
struct DynamicsConfig {
  double pinion_mass = 0.0, gear_mass = 0.0;        ///< [kg]
  double pinion_inertia = 0.0, gear_inertia = 0.0;  ///< [kg m^2]
  double mesh_damping_ratio = 0.05;                 ///< of the torsional mode: c_s = 2 zeta sqrt(k_mean m_s)
  double bearing_damping_ratio = 0.02;              ///< of each shaft on its bearing: c_b = 2 zeta sqrt(k_r m)
  std::array<double, 2> bearing_clearance{{0.0, 0.0}};  ///< radial half-gap [m]
  double speed_rpm = 1000.0;                        ///< pinion speed
  double transmission_error_amplitude = 0.0;        ///< manufacturing TE at mesh frequency [m]
  double backlash = 0.0;                            ///< half backlash of an ordinary gear [m]
  double torque = 0.1;                              ///< mean pinion torque [N·m]
  bool present = false;                             ///< the block was given
};

struct RigConfig {
  GearPairSpec gears;
  AntiBacklashSpec anti_backlash;          ///< spring_stiffness 0 = an ordinary (single) gear
  MeshStiffnessModel mesh_model = MeshStiffnessModel::kPotentialEnergy;
  int mesh_samples = 256;                  ///< table samples over the path of contact
  std::vector<BearingSupportConfig> bearings;
  DynamicsConfig dynamics;
};

}  // namespace drivetrain_stiffness

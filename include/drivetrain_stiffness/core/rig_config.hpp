// A rig's description as the YAML loader fills it (docs/configuration.md); SI units.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/bearing/bearing_support.hpp"
#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/gear/gear_geometry.hpp"

namespace drivetrain_stiffness {

/// One bearing support and its operating settings.
struct BearingSupportConfig {
  std::string name;  ///< e.g. "pinion_bearing"
  BallBearingSpec spec;
  Arrangement arrangement = Arrangement::kSingle;
  TiltCondition tilt = TiltCondition::kConstrained;
  double axial_preload = 0.0;    ///< [N]
  double radial_preload = 0.0;   ///< [N] besides the mesh force
  Interference interference;     ///< [m] diametral
  int shaft = 0;                 ///< 0 pinion, 1 gear
  double mesh_load_share = 1.0;  ///< [-] of the mesh force
  double stiffness_scale = 1.0;  ///< [-] on the Hertz model's stiffness
};

/// The `dynamics:` block.
struct DynamicsConfig {
  double pinion_mass = 0.0, gear_mass = 0.0;            ///< [kg]
  double pinion_inertia = 0.0, gear_inertia = 0.0;      ///< [kg m^2]
  double mesh_damping_ratio = 0.05;                     ///< [-] in [0, 1]
  double bearing_damping_ratio = 0.02;                  ///< [-] in [0, 1]
  std::array<double, 2> bearing_clearance{{0.0, 0.0}};  ///< [m] radial half-gap
  double speed_rpm = 1000.0;                            ///< [rpm] pinion
  double transmission_error_amplitude = 0.0;            ///< [m] at mesh frequency
  double backlash = 0.0;                                ///< [m] half, ordinary gear
  double torque = 0.1;                                  ///< [N·m] mean pinion torque
  bool present = false;
};

/// One calibrated parameter's prior.
struct CalibrationPrior {
  double mean = 0.0;
  double std = 0.0;             ///< 0: held at `mean`
  double reference_std = -1.0;  ///< the drawing's spread (docs/tools.md --calibrate); < 0: `std`
  double reference() const { return reference_std >= 0.0 ? reference_std : std; }
};

/// The `calibration:` block (docs/calibration.md "3. The estimator").
struct CalibrationConfig {
  bool present = false;
  CalibrationPrior mesh_stiffness_scale{1.0, 0.2};  ///< [-]
  CalibrationPrior pinion_bearing_scale{1.0, 0.3};  ///< [-]
  CalibrationPrior gear_bearing_scale{1.0, 0.3};    ///< [-]
  CalibrationPrior preload_torque{1.0, 0.2};        ///< [N·m] T_p about the gear axis
  CalibrationPrior te_offset{0.0, 1e-6};            ///< [m]
  double baseline_torque = 0.05;                    ///< [N·m]
  double torque_band = 0.02;                        ///< [N·m]
  double min_speed_rpm = 5.0;                       ///< [rpm]
  double max_mesh_to_natural = 0.1;                 ///< [-]
  double gate = 16.27;                              ///< NIS (chi^2, 3 dof, 0.999)
  double model_error = 0.01;                        ///< [-] relative
  double modal_model_error = 0.002;                 ///< [-] relative, per natural frequency
  double te_noise_floor = 2e-9;                     ///< [m]
  double drift = 1e-4;                              ///< [1/sqrt(s)] relative
  double reference_torque = 1.0;                    ///< [N·m] of series_compliance
};

struct RigConfig {
  GearPairSpec gears;
  AntiBacklashSpec anti_backlash;  ///< spring_stiffness 0: an ordinary gear
  MeshStiffnessModel mesh_model = MeshStiffnessModel::kPotentialEnergy;
  int mesh_samples = 256;             ///< table samples over the path of contact
  double mesh_stiffness_scale = 1.0;  ///< [-] on the tooth pairs, not the spring
  std::vector<BearingSupportConfig> bearings;
  DynamicsConfig dynamics;
  CalibrationConfig calibration;
};

}  // namespace drivetrain_stiffness

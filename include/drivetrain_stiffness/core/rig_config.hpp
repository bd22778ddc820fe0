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
  std::string name;  ///< e.g. "pinion_bearing"
  BallBearingSpec spec;
  Arrangement arrangement = Arrangement::kSingle;
  TiltCondition tilt = TiltCondition::kConstrained;
  double axial_preload = 0.0;    ///< [N]
  double radial_preload = 0.0;   ///< external radial load besides the mesh force [N]
  Interference interference;     ///< diametral [m]
  int shaft = 0;                 ///< 0 pinion, 1 gear
  double mesh_load_share = 1.0;  ///< fraction of the mesh force this support reacts
  /// [-] scale on the support's stiffness from the Hertz model (its compliance divided by it): 1
  /// for the drawing's bearing, a calibrated value from `drivetrain_replay --calibrate`
  /// (docs/calibration.md).
  double stiffness_scale = 1.0;
};

/// The `dynamics:` block: what the 3-DOF model needs beyond the gears and bearings (SI units).
struct DynamicsConfig {
  double pinion_mass = 0.0, gear_mass = 0.0;        ///< [kg]
  double pinion_inertia = 0.0, gear_inertia = 0.0;  ///< [kg m^2]
  double mesh_damping_ratio =
      0.05;  ///< of the torsional mode: c_s = 2 zeta sqrt(k_mean m_s); [0, 1] (requireDampingRatio)
  double bearing_damping_ratio =
      0.02;  ///< of each shaft on its bearing: c_b = 2 zeta sqrt(k_r m); [0, 1]
  std::array<double, 2> bearing_clearance{{0.0, 0.0}};  ///< radial half-gap [m]
  double speed_rpm = 1000.0;                            ///< pinion speed
  double transmission_error_amplitude = 0.0;            ///< manufacturing TE at mesh frequency [m]
  double backlash = 0.0;                                ///< half backlash of an ordinary gear [m]
  double torque = 0.1;                                  ///< mean pinion torque [N·m]
  bool present = false;                                 ///< the block was given
};

/// One calibrated parameter's prior: its mean and standard deviation (docs/calibration.md).
struct CalibrationPrior {
  double mean = 0.0;
  double std = 0.0;  ///< 0: the parameter is held at `mean` (not estimated)
  /// The drawing's spread, which `identified` (the posterior std below half of it) and the drift
  /// are judged against; negative: `std`. A calibrated gearbox (drivetrain_replay --calibrate)
  /// starts from the last posterior as `std` and keeps the drawing's spread here, so a parameter
  /// determined before is not reported "not identified" because the new data did not halve a std
  /// that is already small, nor does a known preload drift more slowly for being known.
  double reference_std = -1.0;
  double reference() const { return reference_std >= 0.0 ? reference_std : std; }
};

/// The gearbox's `calibration:` block: the live calibration's priors and its data rules
/// (docs/calibration.md). Absent: no calibration.
struct CalibrationConfig {
  bool present = false;
  CalibrationPrior mesh_stiffness_scale{1.0, 0.2};  ///< [-] scale on the tooth-pair stiffness
  CalibrationPrior pinion_bearing_scale{
      1.0, 0.3};  ///< [-] scale on the pinion shaft's bearing stiffness
  CalibrationPrior gear_bearing_scale{1.0,
                                      0.3};  ///< [-] scale on the gear shaft's bearing stiffness
  CalibrationPrior preload_torque{
      1.0, 0.2};  ///< [N·m] anti-backlash preload torque T_p about the gear axis
  CalibrationPrior te_offset{0.0, 1e-6};  ///< [m] offset of the measured TE left after the baseline
  double baseline_torque =
      0.05;  ///< [N·m] windows with |mean torque| at most this build the unloaded baseline
  double torque_band =
      0.02;  ///< [N·m] a window ends when the torque leaves its start by more (plus 1 %)
  double min_speed_rpm =
      5.0;  ///< [rpm] slower windows are not excited (too few mesh periods per second)
  /// [-] windows whose mesh frequency exceeds this fraction of the lowest natural frequency are not
  /// quasi-static (dynamic amplification (f/f_n)^2 above ~1e-2) and are not used.
  double max_mesh_to_natural = 0.1;
  double gate =
      16.27;  ///< normalised innovation squared above this (chi^2, 3 dof, 0.999) rejects a window
  double model_error = 0.01;     ///< [-] relative model error added to each feature's variance
  double te_noise_floor = 2e-9;  ///< [m] absolute floor of each feature's standard deviation
  double drift = 1e-4;  ///< [1/sqrt(s)] random walk of the scales (relative), preload and offset
  double reference_torque = 1.0;  ///< [N·m] pinion torque at which series_compliance is reported
};

struct RigConfig {
  GearPairSpec gears;
  AntiBacklashSpec anti_backlash;  ///< spring_stiffness 0 = an ordinary (single) gear
  MeshStiffnessModel mesh_model = MeshStiffnessModel::kPotentialEnergy;
  int mesh_samples = 256;  ///< table samples over the path of contact
  /// [-] scale on the tooth-pair stiffness of both halves (not the scissor spring): 1 for the
  /// drawing's gear, a calibrated value from `drivetrain_replay --calibrate` (docs/calibration.md).
  double mesh_stiffness_scale = 1.0;
  std::vector<BearingSupportConfig> bearings;
  DynamicsConfig dynamics;
  CalibrationConfig calibration;
};

}  // namespace drivetrain_stiffness

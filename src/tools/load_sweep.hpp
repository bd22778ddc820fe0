// The load_sweep scenario (docs/tools.md): a calibration recording whose true rig is known. The
// rig turns at a constant speed through a torque staircase that crosses the anti-backlash knee in
// both directions, and the gear encoder carries the TRUE rig's transmission error, from the 3-DOF
// dynamics of the true rig (a RigPipeline on it) with the bearings' static deflection made exact
// (the secant, not the tangent: see makeLoadSweep). The true rig is the RigConfig given: its
// mesh.stiffness_scale, bearings[].stiffness_scale and anti_backlash.preload_torque are the truth
// the calibration (calibration/calibrator.hpp) should find. ROS-free and deterministic for a seed.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "rig_scenarios.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {

constexpr double kArcsecond = kPi / (180.0 * 3600.0);  ///< [rad]

struct LoadSweepSpec {
  double speed_rpm = 120.0;     ///< [rpm] constant pinion speed (> 0)
  double torque_rate = 1000.0;  ///< [Hz] torque messages
  double joint_rate = 5000.0;   ///< [Hz] encoder readings (joint_states)
  bool joint_velocity = true;   ///< false: the readings carry no velocity
  /// [s] 0: the natural length (the holds below, in gear turns); > 0: every hold scaled so that the
  /// scenario lasts this long.
  double duration = 0.0;
  std::uint64_t seed = 1;
  double baseline_turns = 3.0;  ///< [gear turns] the unloaded hold at the start
  double step_turns = 2.5;      ///< [gear turns] every later hold
  int positive_levels = 10;     ///< levels above zero, the knee halfway between two of them
  int negative_levels = 6;      ///< levels below zero, the reverse knee halfway between two of them
  double overdrive = 1.5;       ///< [-] the top level about this times the knee (each direction)
  double eccentricity_min = 10.0 * kArcsecond;  ///< [rad] range of each encoder's mounting error
  double eccentricity_max = 20.0 * kArcsecond;
  double stamp_jitter = 20e-6;  ///< [s] joint_states header stamps: true time + uniform(+-this)
  double torque_noise =
      0.005;  ///< [-] published torque: sigma = torque_noise |T| + torque_noise_floor
  double torque_noise_floor = 1e-3;  ///< [N*m]
  double lead_in = 0.1;              ///< [s] the truth dynamics run this long before t = 0
  /// [s] a final hold at `dwell_torque` after the sweep, for the calibration's drift at constant
  /// load (drivetrain_calibration_mc --dwell); 0: none. Not scaled by `duration`.
  double dwell = 0.0;
  double dwell_torque = 3.0;  ///< [N*m] the dwell's pinion torque (within the bearings' limit)
};

/// One hold of the true torque: [t0, t1) [s].
struct LoadSweepLevel {
  double t0 = 0.0, t1 = 0.0, torque = 0.0;
};

struct LoadSweepTruth {
  double mesh_stiffness_scale = 1.0;                ///< rig.mesh_stiffness_scale
  std::array<double, 2> bearing_scale{{1.0, 1.0}};  ///< stiffness_scale of each shaft's supports
  double preload_torque = 0.0;                      ///< [N*m] anti_backlash.preload_torque
  double knee_torque = 0.0;                         ///< [N*m] where the back half lifts (> 0)
  double reverse_knee_torque = 0.0;                 ///< [N*m] where the drive half lifts (< 0)
  double gear_turn = 0.0;                           ///< [s] one gear revolution
  double duration = 0.0;                            ///< [s]
  std::vector<LoadSweepLevel> levels;
  std::array<double, 2> eccentricity{{0.0, 0.0}};        ///< [rad] pinion, gear encoder
  std::array<double, 2> eccentricity_phase{{0.0, 0.0}};  ///< [rad]
  /// The calibration's parameters of the true rig (te_offset 0).
  CalibrationVector parameters() const;
};

struct LoadSweep {
  std::vector<RigEvent> events;  ///< in send order: readings, the preload at t = 0, torque
  LoadSweepTruth truth;
  /// [m] the true encoder TE x_enc = r_b,p theta_p + r_b,g theta_g at each reading (before the
  /// encoders' mounting error and quantisation), in reading order.
  std::vector<double> te;
};

/// The scenario on the true rig `rig` (needs its dynamics block). Throws InvalidInput naming the
/// field for a bad spec or rig, and if the truth dynamics refuse an input.
LoadSweep makeLoadSweep(const RigConfig& rig, const LoadSweepSpec& spec);
/// Natural duration [s] of the staircase for `spec` (spec.duration ignored).
double loadSweepNaturalDuration(const RigConfig& rig, const LoadSweepSpec& spec);

}  // namespace drivetrain_stiffness

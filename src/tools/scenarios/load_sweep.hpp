// The load_sweep scenario: a calibration recording whose true rig is the RigConfig given
// (docs/tools.md "load_sweep"). Deterministic for a seed.
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
  double speed_rpm = 120.0;     ///< [rpm] > 0
  double torque_rate = 1000.0;  ///< [Hz]
  double joint_rate = 5000.0;   ///< [Hz]
  bool joint_velocity = true;
  double duration = 0.0;  ///< [s] 0: the natural length; > 0: every hold scaled to it
  std::uint64_t seed = 1;
  double baseline_turns = 3.0;                  ///< [gear turns] the unloaded hold at the start
  double step_turns = 2.5;                      ///< [gear turns] every later hold
  int positive_levels = 10;                     ///< the knee halfway between two of them
  int negative_levels = 6;                      ///< the reverse knee halfway between two of them
  double overdrive = 1.5;                       ///< [-] the top level over the knee
  double eccentricity_min = 10.0 * kArcsecond;  ///< [rad] encoder mounting error range
  double eccentricity_max = 20.0 * kArcsecond;
  double stamp_jitter = 20e-6;       ///< [s] uniform, on the joint_states stamps
  double torque_noise = 0.005;       ///< [-] sigma = torque_noise |T| + torque_noise_floor
  double torque_noise_floor = 1e-3;  ///< [N*m]
  double lead_in = 0.1;              ///< [s] of truth dynamics before t = 0
  double dwell = 0.0;                ///< [s] a final hold at `dwell_torque`, not scaled; 0: none
  double dwell_torque = 3.0;         ///< [N*m]
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
  /// [m] the true encoder TE x_enc = r_b,p theta_p + r_b,g theta_g at each reading, before the
  /// mounting error and quantisation.
  std::vector<double> te;
};

/// The scenario on the true rig `rig` (needs its dynamics block). Throws InvalidInput naming the
/// field for a bad spec or rig, and if the truth dynamics refuse an input.
LoadSweep makeLoadSweep(const RigConfig& rig, const LoadSweepSpec& spec);
/// Natural duration [s] of the staircase for `spec` (spec.duration ignored).
double loadSweepNaturalDuration(const RigConfig& rig, const LoadSweepSpec& spec);

}  // namespace drivetrain_stiffness

// The pipeline's settings (the node's private parameters, docs/ros_api.md "Parameters"), validated
// in one place. ROS-free.
#pragma once

#include <string>
#include <vector>

#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/vibration_channels.hpp"

namespace drivetrain_stiffness {

/// Settings of the pipeline (the node's private parameters). validate() names the field and value.
struct PipelineOptions {
  EstimatorLimits limits = onlineLimits();  ///< limits.load_tolerance: ~bearing_load_tolerance
  static EstimatorLimits onlineLimits() {
    EstimatorLimits l;
    // 1e-3 of the support load: the stiffness lags by ~3e-4, far inside the 1 % at which the
    // dynamics take up a change (on a 1 % grid) and the resonance republishes; ripple no longer
    // re-solves every bearing.
    l.load_tolerance = 1e-3;
    return l;
  }
  bool dynamics = true;         ///< integrate the 3-DOF model (needs the gearbox's dynamics block)
  double output_rate = 1000.0;  ///< [Hz] transmission_error rate, rounded to divide the mesh period
  double max_gap = 1.0;         ///< [s] a longer forward input gap restarts the dynamics
  double stamp_jump_back = 1.0;  ///< [s] a stamp further back than this restarts everything
  /// [s] the clock going back by more resets everything: a looping bag, not an ntpd or chrony step
  /// (why 1 s: docs/reliability.md).
  double clock_jump_back = 1.0;
  double resonance_threshold = 0.01;  ///< [-] relative frequency change that republishes resonance
  int spectrum_window = 1024;         ///< [samples] TE spectrum window
  int spectrum_hop = 256;             ///< [samples] between spectra
  double pinion_speed_rpm = 1000.0;   ///< [rpm] nominal speed for the mesh phase
  std::string torque_frame;           ///< required header.frame_id of torque inputs; empty = any
  double mesh_phase_offset =
      0.0;  ///< [-] mesh phase at measured pinion angle 0 (where a drive pair enters contact)
  double motion_timeout = 0.1;  ///< [s] no joint_states for this long: back to ~pinion_speed_rpm
  double gear_ratio_tolerance =
      0.01;                 ///< [rad] gear angle off -(z_p/z_g) pinion angle by more: reported
  int motion_slices = 256;  ///< slices per mesh period of the measured-motion dynamics
  bool calibrate = true;    ///< the calibration rule, with a calibration block in the gearbox
  /// Vibration channels named otherwise than a bearing support (docs/vibration.md "Input").
  std::vector<VibrationChannelAlias> vibration_channels;
  double vibration_record = 4.0;  ///< [s] of accelerations kept for the identification
  void validate() const;
};

}  // namespace drivetrain_stiffness

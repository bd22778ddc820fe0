// The pipeline's settings: the node's private parameters (docs/ros_api.md "Parameters").
#pragma once

#include <string>
#include <vector>

#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/vibration_channels.hpp"

namespace drivetrain_stiffness {

/// The node's private parameters, each described in docs/ros_api.md under its name.
struct PipelineOptions {
  EstimatorLimits limits = onlineLimits();  ///< load_tolerance: ~bearing_load_tolerance
  static EstimatorLimits onlineLimits() {
    EstimatorLimits l;
    l.load_tolerance = 1e-3;
    return l;
  }
  bool dynamics = true;
  double output_rate = 1000.0;         ///< [Hz]
  double max_gap = 1.0;                ///< [s]
  double stamp_jump_back = 1.0;        ///< [s]
  double clock_jump_back = 1.0;        ///< [s]
  double resonance_threshold = 0.01;   ///< [-]
  int spectrum_window = 1024;          ///< [samples]
  int spectrum_hop = 256;              ///< [samples]
  double pinion_speed_rpm = 1000.0;    ///< [rpm]
  std::string torque_frame;            ///< empty: any
  double mesh_phase_offset = 0.0;      ///< [-]
  double motion_timeout = 0.1;         ///< [s]
  double gear_ratio_tolerance = 0.01;  ///< [rad]
  int motion_slices = 256;
  bool calibrate = true;
  /// Vibration channels named otherwise than a bearing support (docs/vibration.md "Input").
  std::vector<VibrationChannelAlias> vibration_channels;
  double vibration_record = 4.0;     ///< [s] of accelerations kept for the identification
  bool modal_identification = true;  ///< identify each renewed vibration record
  int modal_max_order = 20;          ///< SSI-COV's last model order (even, 4 to 60)
  int modal_block_rows = 40;         ///< SSI-COV's block rows (lags to 2i - 1; 2 to 200)
  /// Lags the SSI-COV Hankel skips (0 to 1000): the span over which the accelerometer chain's
  /// anti-alias filter correlates the noise and the direct term [samples].
  int modal_skipped_lags = 32;
  /// The accelerometer chain's flat band as a fraction of the sample rate (its anti-alias filter's
  /// pass band, (0, 0.5]); poles above it are set aside [-].
  double modal_band = 0.35;
  /// Identify on a worker thread (the node); off: in the caller's thread (a replay). The outputs
  /// are the same bits either way.
  bool modal_worker = false;
  /// Throws InvalidInput naming the parameter and its value.
  void validate() const;
};

}  // namespace drivetrain_stiffness

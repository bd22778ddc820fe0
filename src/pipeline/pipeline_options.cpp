#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"

#include <cmath>
#include <string>

#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

void PipelineOptions::validate() const {
  limits.validate(
      "bearing_load_tolerance");  // StiffnessEstimator's rules, under the parameter's name
  requirePositive("output_rate", output_rate);
  if (output_rate > 1e6)
    throw InvalidInput("output_rate = " + formatValue(output_rate) + ": must be <= 1e6 Hz");
  requirePositive("max_gap", max_gap);
  if (max_gap * output_rate > DynamicsEstimator::kMaxSamplesPerAdvance) {
    throw InvalidInput("max_gap = " + formatValue(max_gap) +
                       ": max_gap * output_rate must be <= 1e7 samples");
  }
  requireNonNegative("stamp_jump_back", stamp_jump_back);
  requireNonNegative("clock_jump_back", clock_jump_back);
  requirePositive("resonance_threshold", resonance_threshold);
  if (resonance_threshold >= 1.0) {
    throw InvalidInput("resonance_threshold = " + formatValue(resonance_threshold) +
                       ": must be < 1 (relative)");
  }
  if (spectrum_window < 8 || spectrum_window > (1 << 20)) {
    throw InvalidInput("spectrum_window = " + std::to_string(spectrum_window) +
                       ": must be in [8, 1048576] samples");
  }
  if (spectrum_hop < 1 || spectrum_hop > spectrum_window) {
    throw InvalidInput("spectrum_hop = " + std::to_string(spectrum_hop) +
                       ": must be in [1, spectrum_window]");
  }
  requireFinite("pinion_speed_rpm", pinion_speed_rpm);
  if (std::abs(pinion_speed_rpm) > 1e5) {
    throw InvalidInput("pinion_speed_rpm = " + formatValue(pinion_speed_rpm) +
                       ": must be within +-1e5 rpm");
  }
  requireFinite("mesh_phase_offset", mesh_phase_offset);
  if (!(mesh_phase_offset >= 0.0 && mesh_phase_offset < 1.0)) {
    throw InvalidInput("mesh_phase_offset = " + formatValue(mesh_phase_offset) +
                       ": must be in [0, 1) (a fraction of a mesh period)");
  }
  requirePositive("motion_timeout", motion_timeout);
  if (motion_timeout > 3600.0)
    throw InvalidInput("motion_timeout = " + formatValue(motion_timeout) + ": must be <= 3600 s");
  requirePositive("gear_ratio_tolerance", gear_ratio_tolerance);
  if (motion_slices < 4 || motion_slices > 65536) {
    throw InvalidInput("motion_slices = " + std::to_string(motion_slices) +
                       ": must be in [4, 65536] per mesh period");
  }
  if (modal_max_order < 4 || modal_max_order > 60 || modal_max_order % 2 != 0) {
    throwInvalid("modal_max_order", modal_max_order, "must be even, from 4 to 60");
  }
  if (!(modal_band > 0.0 && modal_band <= 0.5)) {
    throwInvalid("modal_band", modal_band, "must be in (0, 0.5] (a fraction of the sample rate)");
  }
  if (modal_block_rows < 2 || modal_block_rows > 200) {
    throwInvalid("modal_block_rows", modal_block_rows, "must be from 2 to 200");
  }
  if (modal_skipped_lags < 0 || modal_skipped_lags > 1000) {
    throwInvalid("modal_skipped_lags", modal_skipped_lags, "must be from 0 to 1000");
  }
  if (!(vibration_record > 0.0 && vibration_record <= 600.0)) {
    throwInvalid("vibration_record", vibration_record, "must be in (0, 600] s");
  }
  if (!torque_frame.empty() && torque_frame.front() == '/') {
    throw InvalidInput("torque_frame = '" + torque_frame +
                       "': a frame id without a leading '/' (or empty: any frame)");
  }
}

}  // namespace drivetrain_stiffness

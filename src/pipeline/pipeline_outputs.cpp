#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

std::vector<std::pair<std::string, std::uint64_t>> namedCounters(const PipelineCounters& c) {
  return {{"accepted_torque", c.accepted_torque},
          {"rejected_torque", c.rejected_torque},
          {"accepted_preload", c.accepted_preload},
          {"rejected_preload", c.rejected_preload},
          {"rejected_zero_stamp", c.zero_stamps},
          {"rejected_out_of_order", c.out_of_order},
          {"rejected_invalid_value", c.invalid_values},
          {"unreachable_loads", c.unreachable_loads},
          {"rejected_wrong_frame", c.wrong_frames},
          {"rejected_stamp_range", c.stamps_out_of_range},
          {"dropped_torque", c.dropped_torque},
          {"dropped_preload", c.dropped_preload},
          {"accepted_joint_states", c.accepted_motion},
          {"rejected_joint_states", c.rejected_motion},
          {"dropped_joint_states", c.dropped_motion},
          {"motion_timeouts", c.motion_timeouts},
          {"gear_ratio_mismatches", c.gear_ratio_mismatches},
          {"stiffness_shed", c.stiffness_shed},
          {"clock_jump_resets", c.clock_resets},
          {"stamp_jump_resets", c.stamp_resets},
          {"gap_restarts", c.gap_restarts},
          {"dynamics_errors", c.dynamics_errors},
          {"stiffness_published", c.stiffness_out},
          {"stiffness_coalesced", c.stiffness_coalesced},
          {"stiffness_refused", c.stiffness_refused},
          {"transmission_error_published", c.te_out},
          {"te_spectra_published", c.spectra_out},
          {"resonance_published", c.resonance_out},
          {"modal_updates", c.modal_updates},
          {"measured_te_published", c.measured_te_out},
          {"calibration_published", c.calibration_out},
          {"calibration_errors", c.calibration_errors},
          {"mesh_period_stats_published", c.mesh_period_stats_out}};
}

}  // namespace drivetrain_stiffness

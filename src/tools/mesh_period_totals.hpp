// A recording's per-mesh-period statistics summed over the whole bag, for drivetrain_replay's
// summary.json and so for a campaign's row (docs/campaign.md, "What it writes"): the pinion speed
// and torque ranges over the blocks, the TE RMS combined by time, the largest block peak-to-peak
// and the time-weighted mean mesh force. Computed from the same values the messages carry, in
// message order, whatever --topics writes.
#pragma once

#include <cstdint>

#include <nlohmann/json.hpp>

#include <drivetrain_stiffness/MeshPeriodStats.h>

namespace drivetrain_stiffness {

class MeshPeriodTotals {
 public:
  /// pinion_teeth: z_p, for the pinion speed 2 pi f_mesh / z_p [rad/s] (signed, as f_mesh).
  explicit MeshPeriodTotals(int pinion_teeth) : pinion_teeth_(pinion_teeth) {}

  void add(const drivetrain_stiffness::MeshPeriodStats& m);

  /// {"blocks", "speed_min", "speed_max" [rad/s], "torque_min", "torque_max" [N*m], "te_rms" (sqrt
  /// of the duration-weighted mean of the blocks' te_rms^2) [m], "te_peak_to_peak" (the largest
  /// block's) [m], "mesh_force_mean" (duration-weighted) [N]}; the figures null without a block
  /// of positive duration.
  nlohmann::json json() const;

 private:
  int pinion_teeth_;
  std::uint64_t blocks_ = 0;
  double speed_min_ = 0.0, speed_max_ = 0.0, torque_min_ = 0.0, torque_max_ = 0.0;
  double weight_ = 0.0, square_ = 0.0, force_ = 0.0, peak_to_peak_ = 0.0;
};

}  // namespace drivetrain_stiffness

// A recording's per-mesh-period statistics summed over the bag for summary.json (docs/campaign.md
// "What it writes").
#pragma once

#include <cstdint>

#include <nlohmann/json.hpp>

#include <drivetrain_stiffness/MeshPeriodStats.h>

namespace drivetrain_stiffness {

class MeshPeriodTotals {
 public:
  /// z_p, for the signed pinion speed 2 pi f_mesh / z_p [rad/s].
  explicit MeshPeriodTotals(int pinion_teeth) : pinion_teeth_(pinion_teeth) {}

  void add(const drivetrain_stiffness::MeshPeriodStats& m);

  /// blocks, speed_min/max [rad/s], torque_min/max [N*m], te_rms (duration-weighted) [m],
  /// te_peak_to_peak (the largest) [m], mesh_force_mean (duration-weighted) [N]; null figures
  /// without a block of positive duration.
  nlohmann::json json() const;

 private:
  int pinion_teeth_;
  std::uint64_t blocks_ = 0;
  double speed_min_ = 0.0, speed_max_ = 0.0, torque_min_ = 0.0, torque_max_ = 0.0;
  double weight_ = 0.0, square_ = 0.0, force_ = 0.0, peak_to_peak_ = 0.0;
};

}  // namespace drivetrain_stiffness

#include "mesh_period_totals.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {

void MeshPeriodTotals::add(const drivetrain_stiffness::MeshPeriodStats& m) {
  // Pinion speed from the mesh frequency: f_mesh = z_p n / 60, so omega_p = 2 pi f_mesh / z_p.
  const double speed = 2.0 * kPi * m.mesh_frequency / pinion_teeth_;
  if (blocks_ == 0) {
    speed_min_ = speed_max_ = speed;
    torque_min_ = torque_max_ = m.torque;
  } else {
    speed_min_ = std::min(speed_min_, speed);
    speed_max_ = std::max(speed_max_, speed);
    torque_min_ = std::min(torque_min_, m.torque);
    torque_max_ = std::max(torque_max_, m.torque);
  }
  ++blocks_;
  weight_ += m.duration;
  square_ += m.duration * (m.te_rms * m.te_rms);
  force_ += m.duration * m.mesh_force_mean;
  peak_to_peak_ = std::max(peak_to_peak_, m.te_peak_to_peak);
}

nlohmann::json MeshPeriodTotals::json() const {
  nlohmann::json j;
  j["blocks"] = blocks_;
  const bool any = blocks_ > 0 && weight_ > 0.0;
  auto value = [&](double v) { return any ? nlohmann::json(v) : nlohmann::json(nullptr); };
  j["speed_min"] = value(speed_min_);
  j["speed_max"] = value(speed_max_);
  j["torque_min"] = value(torque_min_);
  j["torque_max"] = value(torque_max_);
  j["te_rms"] = value(any ? std::sqrt(square_ / weight_) : 0.0);
  j["te_peak_to_peak"] = value(peak_to_peak_);
  j["mesh_force_mean"] = value(any ? force_ / weight_ : 0.0);
  return j;
}

}  // namespace drivetrain_stiffness

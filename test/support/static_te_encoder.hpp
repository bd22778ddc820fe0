// Encoder readings of a rig whose gear angle carries the calibration's own static TE at the nominal
// parameters (StaticTeModel), at one loaded torque: what the calibration tests, the allocation
// test and the calibration benchmark feed when every loaded window must pass the gate. Zero
// torque gives zero TE (the baseline), plus an optional manufacturing TE at the mesh frequency.
#pragma once

#include <array>
#include <cmath>

#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/motion.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

namespace drivetrain_stiffness::test {

class StaticTeEncoder {
 public:
  /// `loaded_torque` [N*m]: the only nonzero torque the readings will carry; `manufacturing` [m]:
  /// amplitude of a sine at the mesh frequency added at every torque.
  StaticTeEncoder(const RigConfig& rig, double loaded_torque, double manufacturing = 0.0)
      : model_(rig),
        loaded_torque_(loaded_torque),
        manufacturing_(manufacturing),
        teeth_(rig.gears.teeth[0]) {
    p_ << 1.0, 1.0, 1.0, rig.anti_backlash.preload_torque, 0.0;
    const StiffnessEstimator supports(rig);
    model_.shaftDeflection(0.0, supports, zero_);
    model_.shaftDeflection(loaded_torque, supports, loaded_);
  }
  /// Mesh phase in [0, 1) at pinion angle theta [rad].
  double phase(double theta) const {
    const double turns = teeth_ * theta / kTwoPi;
    return turns - std::floor(turns);
  }
  /// The gear angle [rad] (joint_states convention) at pinion angle theta under `torque` (0 or the
  /// loaded torque): x = r_b,p theta + r_b,g theta_g.
  double gearAngle(double theta, double torque) const {
    const double ph = phase(theta);
    const double x =
        (torque == 0.0 ? 0.0 : model_.at(p_, ph, loaded_torque_, loaded_, 0.0, zero_)) +
        manufacturing_ * std::sin(kTwoPi * ph);
    return (x - model_.baseRadius()[0] * theta) / model_.baseRadius()[1];
  }
  /// The reading at pinion angle theta and speed w, angles reduced to a turn and, with `count` >
  /// 0, quantised to that many radians.
  MotionInput reading(double theta, double w, double torque, double count = 0.0) const {
    auto q = [&](double a) { return count > 0.0 ? std::round(a / count) * count : a; };
    MotionInput m;
    m.pinion_angle = q(std::remainder(theta, kTwoPi));
    m.pinion_velocity = w;
    m.gear_angle = q(std::remainder(gearAngle(theta, torque), kTwoPi));
    return m;
  }
  const StaticTeModel& model() const { return model_; }
  const CalibrationVector& parameters() const { return p_; }
  const std::array<double, 2>& zeroShafts() const { return zero_; }
  const std::array<double, 2>& loadedShafts() const { return loaded_; }

 private:
  StaticTeModel model_;
  double loaded_torque_, manufacturing_;
  int teeth_;
  CalibrationVector p_;
  std::array<double, 2> zero_{}, loaded_{};
};

}  // namespace drivetrain_stiffness::test

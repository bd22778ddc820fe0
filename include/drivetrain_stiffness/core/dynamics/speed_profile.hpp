// The pinion's speed omega(t) [rad/s] and angle theta(t) = integral_0^t omega [rad] in closed form:
// piecewise linear or half-cosine spans between knots, the speed continuous and held outside them.
#pragma once

#include <vector>

namespace drivetrain_stiffness {

/// `from` until `start`, linearly to `to` at `end`, then held.
struct SpeedRamp {
  double from = 0.0;   ///< [rad/s]
  double to = 0.0;     ///< [rad/s]
  double start = 0.0;  ///< [s]
  double end = 1.0;    ///< [s] > start
};

struct SpeedStep {
  double time = 0.0;   ///< [s] the ramp to `speed` starts here
  double speed = 0.0;  ///< [rad/s] reached at time + ramp_duration
};

/// `initial`, then each step a linear ramp of `ramp_duration` to its speed; steps must not overlap.
struct SpeedSteps {
  double initial = 0.0;          ///< [rad/s]
  std::vector<SpeedStep> steps;  ///< in increasing time
  double ramp_duration = 0.05;   ///< [s] > 0
};

/// omega = speed cos(2 pi (t - start) / period) over one period, `speed` before and after.
struct SpeedReversal {
  double speed = 0.0;   ///< [rad/s] > 0
  double start = 0.0;   ///< [s]
  double period = 1.0;  ///< [s] > 0
};

/// [rad/s] the largest speed taken (about 1e6 rpm).
constexpr double kMaxShaftSpeed = 1e5;

class SpeedProfile {
 public:
  /// A constant speed [rad/s]. Each constructor throws InvalidInput naming the field.
  explicit SpeedProfile(double speed);
  explicit SpeedProfile(const SpeedRamp& ramp);
  explicit SpeedProfile(const SpeedSteps& steps);
  explicit SpeedProfile(const SpeedReversal& reversal);

  double speed(double t) const;  ///< omega(t) [rad/s]
  double angle(double t) const;  ///< theta(t) = integral_0^t omega [rad]

 private:
  enum class Shape { kLinear, kHalfCosine };
  struct Span {
    double begin = 0.0, end = 0.0;  ///< [s]
    double from = 0.0, to = 0.0;    ///< [rad/s] speed at begin and end
    Shape shape = Shape::kLinear;
    double angle_at_begin = 0.0;  ///< [rad] from the first knot
  };
  void addSpan(double begin, double end, double from, double to, Shape shape);
  double angleFromFirstKnot(double t) const;

  double initial_speed_ = 0.0;  ///< [rad/s] before the first knot
  std::vector<Span> spans_;     ///< contiguous
  double angle_at_zero_ = 0.0;  ///< angleFromFirstKnot(0)
};

}  // namespace drivetrain_stiffness

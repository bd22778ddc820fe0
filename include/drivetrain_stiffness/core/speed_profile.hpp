// The pinion's speed omega(t) [rad/s] and angle theta(t) [rad] = integral from 0 to t of omega,
// both in closed form (no quadrature), for the rig's speed scenarios: constant, a linear ramp
// (run-up, coast-down), speed steps each taken by a short linear ramp, and a reversal through
// zero (a cosine). theta(0) = 0. ROS-free.
//
// Every profile is piecewise: knots t_0 < ... < t_m with the speed at each knot, and on each span
// either a linear ramp or a half cosine between the knots' speeds; the speed is held before t_0 and
// after t_m. The speed is continuous everywhere, so the angle is C1.
#pragma once

#include <vector>

namespace drivetrain_stiffness {

/// Linear ramp: `from` until `start`, linearly to `to` at `end`, then held.
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

/// Speed steps: `initial` until the first step; each step a linear ramp of `ramp_duration` from the
/// level before it to its own speed. Steps must not overlap: time[i+1] >= time[i] + ramp_duration.
struct SpeedSteps {
  double initial = 0.0;          ///< [rad/s]
  std::vector<SpeedStep> steps;  ///< in increasing time
  double ramp_duration = 0.05;   ///< [s] > 0
};

/// Reversal: omega = speed cos(2 pi (t - start) / period) over [start, start + period], held at
/// `speed` before and after: +speed, zero at start + period/4, -speed at start + period/2, zero
/// again at start + 3 period/4, +speed at start + period.
struct SpeedReversal {
  double speed = 0.0;   ///< [rad/s] > 0
  double start = 0.0;   ///< [s]
  double period = 1.0;  ///< [s] > 0
};

/// Speeds past this are refused [rad/s]: about 1e6 rpm, an order of magnitude past any shaft made
/// (and a bound that keeps speed times time finite).
constexpr double kMaxShaftSpeed = 1e5;

class SpeedProfile {
 public:
  /// Constant speed [rad/s] (the field is named `speed` in errors).
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
    double angle_at_begin = 0.0;  ///< [rad] integral of omega from the first knot to begin
  };
  void addSpan(double begin, double end, double from, double to, Shape shape);
  /// Integral of omega from the first knot to t [rad].
  double angleFromFirstKnot(double t) const;

  double initial_speed_ = 0.0;  ///< [rad/s] before the first knot (all of time if there is none)
  std::vector<Span> spans_;     ///< contiguous: spans_[i].end == spans_[i + 1].begin
  double angle_at_zero_ = 0.0;  ///< angleFromFirstKnot(0), so that angle(0) = 0
};

}  // namespace drivetrain_stiffness

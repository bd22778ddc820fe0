#include "drivetrain_stiffness/core/dynamics/speed_profile.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

/// Times past this are refused [s] (about 32 years): keeps speed times time far from overflow.
constexpr double kMaxTime = 1e9;

void requireSpeed(const std::string& field, double value) {
  requireFinite(field, value);
  if (!(std::abs(value) <= kMaxShaftSpeed)) {
    throwInvalid(field, value,
                 "must lie in [-" + formatValue(kMaxShaftSpeed) + ", " +
                     formatValue(kMaxShaftSpeed) + "] rad/s");
  }
}

void requireTime(const std::string& field, double value) {
  requireFinite(field, value);
  if (!(std::abs(value) <= kMaxTime)) throwInvalid(field, value, "must lie in [-1e9, 1e9] s");
}

void requireDuration(const std::string& field, double value) {
  requirePositive(field, value);
  requireAtMost(field, value, kMaxTime);
}

}  // namespace

SpeedProfile::SpeedProfile(double speed) : initial_speed_(speed) { requireSpeed("speed", speed); }

SpeedProfile::SpeedProfile(const SpeedRamp& r) : initial_speed_(r.from) {
  requireSpeed("speed_ramp.from", r.from);
  requireSpeed("speed_ramp.to", r.to);
  requireTime("speed_ramp.start", r.start);
  requireTime("speed_ramp.end", r.end);
  if (!(r.end > r.start))
    throwInvalid("speed_ramp.end", r.end, "must be > speed_ramp.start = " + formatValue(r.start));
  addSpan(r.start, r.end, r.from, r.to, Shape::kLinear);
}

SpeedProfile::SpeedProfile(const SpeedSteps& s) : initial_speed_(s.initial) {
  requireSpeed("speed_steps.initial", s.initial);
  requireDuration("speed_steps.ramp_duration", s.ramp_duration);
  double level = s.initial;
  for (std::size_t i = 0; i < s.steps.size(); ++i) {
    const std::string field = "speed_steps.steps[" + std::to_string(i) + "]";
    const SpeedStep& step = s.steps[i];
    requireTime(field + ".time", step.time);
    requireSpeed(field + ".speed", step.speed);
    if (i > 0) {
      const double previous_end = s.steps[i - 1].time + s.ramp_duration;
      if (!(step.time >= previous_end)) {
        throwInvalid(field + ".time", step.time,
                     "must be >= the previous step's time + speed_steps.ramp_duration = " +
                         formatValue(previous_end) + " (the ramps must not overlap)");
      }
      if (step.time > spans_.back().end)
        addSpan(spans_.back().end, step.time, level, level, Shape::kLinear);  // hold
    }
    addSpan(step.time, step.time + s.ramp_duration, level, step.speed, Shape::kLinear);
    level = step.speed;
  }
}

SpeedProfile::SpeedProfile(const SpeedReversal& r) : initial_speed_(r.speed) {
  requireSpeed("speed_reversal.speed", r.speed);
  if (!(r.speed > 0.0))
    throwInvalid("speed_reversal.speed", r.speed, "must be > 0 (it reverses to -speed)");
  requireTime("speed_reversal.start", r.start);
  requireDuration("speed_reversal.period", r.period);
  // speed cos(2 pi (t - start) / period) as two half cosines: +speed -> -speed -> +speed.
  const double middle = r.start + 0.5 * r.period;
  addSpan(r.start, middle, r.speed, -r.speed, Shape::kHalfCosine);
  addSpan(middle, r.start + r.period, -r.speed, r.speed, Shape::kHalfCosine);
}

void SpeedProfile::addSpan(double begin, double end, double from, double to, Shape shape) {
  Span s{begin, end, from, to, shape, 0.0};
  if (!spans_.empty()) {
    const Span& last = spans_.back();
    // Over a whole span both shapes integrate to the mean speed times the duration: linear,
    // (from + to) D / 2 (trapezoid, exact for a linear function); half cosine,
    // integral_0^D [m + h cos(pi tau / D)] dtau = m D + h D sin(pi) / pi = m D with m = (from + to)
    // / 2.
    s.angle_at_begin = last.angle_at_begin + 0.5 * (last.from + last.to) * (last.end - last.begin);
  }
  spans_.push_back(s);
  angle_at_zero_ = angleFromFirstKnot(0.0);
}

double SpeedProfile::speed(double t) const {
  if (spans_.empty() || t < spans_.front().begin) return initial_speed_;
  if (t >= spans_.back().end) return spans_.back().to;
  const auto it = std::upper_bound(spans_.begin(), spans_.end(), t,
                                   [](double x, const Span& s) { return x < s.begin; }) -
                  1;
  const double u = (t - it->begin) / (it->end - it->begin);  // in [0, 1)
  if (it->shape == Shape::kLinear) return it->from + (it->to - it->from) * u;
  // Half cosine between the knots' speeds: m + h cos(pi u), m = (from + to) / 2, h = (from - to)
  // / 2.
  return 0.5 * (it->from + it->to) + 0.5 * (it->from - it->to) * std::cos(kPi * u);
}

double SpeedProfile::angleFromFirstKnot(double t) const {
  if (spans_.empty()) return initial_speed_ * t;  // no knot: measured from t = 0
  const Span& first = spans_.front();
  if (t < first.begin) return initial_speed_ * (t - first.begin);
  const Span& last = spans_.back();
  if (t >= last.end) {
    // The last span whole (mean speed times duration, as in addSpan), then the held speed.
    return last.angle_at_begin + 0.5 * (last.from + last.to) * (last.end - last.begin) +
           last.to * (t - last.end);
  }
  const auto it = std::upper_bound(spans_.begin(), spans_.end(), t,
                                   [](double x, const Span& s) { return x < s.begin; }) -
                  1;
  const double d = it->end - it->begin, tau = t - it->begin;
  if (it->shape == Shape::kLinear) {
    // integral_0^tau [a + (b - a) s / D] ds = a tau + (b - a) tau^2 / (2 D)
    return it->angle_at_begin + it->from * tau + 0.5 * (it->to - it->from) * tau * tau / d;
  }
  // integral_0^tau [m + h cos(pi s / D)] ds = m tau + h D sin(pi tau / D) / pi
  const double m = 0.5 * (it->from + it->to), h = 0.5 * (it->from - it->to);
  return it->angle_at_begin + m * tau + h * d * std::sin(kPi * tau / d) / kPi;
}

double SpeedProfile::angle(double t) const { return angleFromFirstKnot(t) - angle_at_zero_; }

}  // namespace drivetrain_stiffness

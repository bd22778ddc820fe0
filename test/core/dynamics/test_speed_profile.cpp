// SpeedProfile: the angle against an independent numerical integral of the speed (trapezoid rule
// on a fine grid, which knows nothing of the profile's pieces), against the closed forms of
// kinematics (constant: theta = omega t; ramp: theta = s0 t + (s1 - s0) t^2 / (2 T); cosine:
// theta = s P sin(2 pi t / P) / (2 pi)), continuity of speed and angle at the knots, the reversal's
// zero crossings, and bad input refused naming the field.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/speed_profile.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

using namespace drivetrain_stiffness;

namespace {

constexpr double kRpm = kTwoPi / 60.0;  // 1 rpm in rad/s (one revolution, 2 pi rad, per 60 s)

/// integral_0^t omega by the trapezoid rule on n intervals: error <= t h^2 max|omega''| / 12 on
/// smooth pieces, and O(h^2 |jump of omega'|) at a knot; h = t / n.
double trapezoid(const SpeedProfile& p, double t, int n = 200000) {
  const double h = t / n;
  double sum = 0.5 * (p.speed(0.0) + p.speed(t));
  for (int k = 1; k < n; ++k) sum += p.speed(k * h);
  return sum * h;
}

/// Expects the message of the InvalidInput thrown by f to start with `field`.
template <typename F>
void expectRefusal(F f, const std::string& field) {
  try {
    f();
    ADD_FAILURE() << "no InvalidInput for " << field;
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()).rfind(field + " = ", 0), 0u) << e.what();
  }
}

}  // namespace

TEST(SpeedProfile, ConstantSpeedTurnsUniformly) {
  const SpeedProfile p(1000.0 * kRpm);
  for (double t : {-0.5, 0.0, 0.3, 2.0}) {
    EXPECT_EQ(p.speed(t), 1000.0 * kRpm);
    EXPECT_NEAR(p.angle(t), 1000.0 * kRpm * t, 1e-12);  // theta = omega t
  }
  EXPECT_EQ(p.angle(0.0), 0.0);
}

TEST(SpeedProfile, RunUpMatchesTheClosedFormAndTheNumericalIntegral) {
  // Run-up 0 -> 6000 rpm over T = 2 s: theta = s0 t + (s1 - s0) t^2 / (2 T).
  const double s0 = 0.0, s1 = 6000.0 * kRpm, T = 2.0;
  EXPECT_NEAR(s1, 628.3185307179587, 1e-12);  // 6000 * 2 pi / 60 = 200 pi
  const SpeedProfile p(SpeedRamp{s0, s1, 0.0, T});
  for (double t : {0.0, 0.25, 1.0, 1.7, 2.0}) {
    EXPECT_NEAR(p.speed(t), s0 + (s1 - s0) * t / T, 1e-12);
    EXPECT_NEAR(p.angle(t), s0 * t + (s1 - s0) * t * t / (2.0 * T), 1e-10);
  }
  for (double t : {0.3, 1.1, 2.0, 2.6})
    EXPECT_NEAR(p.angle(t), trapezoid(p, t), 1e-7) << "t = " << t;
  // Held after the ramp: theta(T) + s1 (t - T), theta(T) = (s0 + s1) T / 2 = 200 pi rad (100
  // revolutions).
  EXPECT_NEAR(p.angle(T), 200.0 * kPi, 1e-10);
  EXPECT_NEAR(p.angle(3.0), 200.0 * kPi + s1 * 1.0, 1e-10);
  EXPECT_EQ(p.speed(5.0), s1);
}

TEST(SpeedProfile, CoastDownWithALateRampMatchesTheClosedForm) {
  // 6000 -> 0 rpm over [0.5, 1.5] s: s0 t before, then s0 t0 + s0 tau + (s1 - s0) tau^2 / (2 T),
  // tau = t - t0.
  const double s0 = 6000.0 * kRpm, s1 = 0.0, t0 = 0.5, t1 = 1.5, T = t1 - t0;
  const SpeedProfile p(SpeedRamp{s0, s1, t0, t1});
  EXPECT_NEAR(p.angle(0.25), s0 * 0.25, 1e-12);
  for (double t : {0.5, 0.8, 1.2, 1.5}) {
    const double tau = t - t0;
    EXPECT_NEAR(p.angle(t), s0 * t0 + s0 * tau + (s1 - s0) * tau * tau / (2.0 * T), 1e-10);
    EXPECT_NEAR(p.angle(t), trapezoid(p, t), 1e-7) << "t = " << t;
  }
  // Stopped: the angle no longer moves.
  EXPECT_EQ(p.speed(2.0), 0.0);
  EXPECT_NEAR(p.angle(4.0), p.angle(t1), 1e-12);
  // Before t = 0 the angle is negative (held speed backwards in time): theta(-0.1) = -0.1 s0.
  EXPECT_NEAR(p.angle(-0.1), -0.1 * s0, 1e-12);
}

TEST(SpeedProfile, RampEndsAreContinuousInSpeedAndAngle) {
  const double s0 = 100.0, s1 = 600.0, t0 = 0.2, t1 = 1.2;
  const SpeedProfile p(SpeedRamp{s0, s1, t0, t1});
  const double eps = 1e-7, slope = (s1 - s0) / (t1 - t0);
  for (double knot : {t0, t1}) {
    // Speed: no jump beyond what the slope gives over eps.
    EXPECT_NEAR(p.speed(knot - eps), p.speed(knot + eps), 2.0 * eps * slope + 1e-9);
    // Angle C1: its central difference across the knot is the speed there (error O(eps slope)).
    const double derivative = (p.angle(knot + eps) - p.angle(knot - eps)) / (2.0 * eps);
    EXPECT_NEAR(derivative, p.speed(knot), 1e-5 * s1) << "knot " << knot;
  }
  EXPECT_NEAR(p.speed(t0), s0, 1e-12);
  EXPECT_NEAR(p.speed(t1), s1, 1e-12);
}

TEST(SpeedProfile, StepsRampBetweenLevelsAndIntegrateExactly) {
  // 500 -> 1000 -> 2000 -> 4000 rpm, dwell 0.5 s, 50 ms ramps.
  SpeedSteps steps;
  steps.initial = 500.0 * kRpm;
  steps.steps = {{0.5, 1000.0 * kRpm}, {1.0, 2000.0 * kRpm}, {1.5, 4000.0 * kRpm}};
  steps.ramp_duration = 0.05;
  const SpeedProfile p(steps);
  EXPECT_NEAR(p.speed(0.25), 500.0 * kRpm, 1e-12);
  EXPECT_NEAR(p.speed(0.525), 750.0 * kRpm, 1e-9);  // mid-ramp: the mean of the two levels
  EXPECT_NEAR(p.speed(0.55), 1000.0 * kRpm, 1e-9);  // ramp done after 50 ms
  EXPECT_NEAR(p.speed(1.3), 2000.0 * kRpm, 1e-12);
  EXPECT_NEAR(p.speed(1.9), 4000.0 * kRpm, 1e-12);
  // By hand: each level's dwell plus each ramp's mean speed times 50 ms.
  const double r = 0.05, w = kRpm;
  const double at2 = 500 * w * 0.5 + 750 * w * r + 1000 * w * (0.5 - r) + 1500 * w * r +
                     2000 * w * (0.5 - r) + 3000 * w * r + 4000 * w * (0.5 - r);
  EXPECT_NEAR(p.angle(2.0), at2, 1e-10);
  for (double t : {0.52, 0.9, 1.53, 2.0})
    EXPECT_NEAR(p.angle(t), trapezoid(p, t), 1e-7) << "t = " << t;
  // C1 at every ramp end.
  for (double knot : {0.5, 0.55, 1.0, 1.05, 1.5, 1.55}) {
    const double eps = 1e-7;
    EXPECT_NEAR((p.angle(knot + eps) - p.angle(knot - eps)) / (2.0 * eps), p.speed(knot), 1e-3)
        << knot;
  }
}

TEST(SpeedProfile, StepsWithAnotherRampDurationAndBackToBackRamps) {
  // Ramps of 0.2 s, the second starting where the first ends (no dwell between).
  const SpeedProfile p(SpeedSteps{0.0, {{0.0, 100.0}, {0.2, -100.0}}, 0.2});
  EXPECT_NEAR(p.speed(0.1), 50.0, 1e-12);
  EXPECT_NEAR(p.speed(0.3), 0.0, 1e-12);
  EXPECT_NEAR(p.speed(0.5), -100.0, 1e-12);
  // theta(0.2) = 100 * 0.2 / 2 = 10; theta(0.4) = 10 + 0 (ramp 100 -> -100 has mean 0).
  EXPECT_NEAR(p.angle(0.2), 10.0, 1e-12);
  EXPECT_NEAR(p.angle(0.4), 10.0, 1e-12);
  EXPECT_NEAR(p.angle(0.5), 0.0, 1e-12);
  EXPECT_NEAR(p.angle(0.37), trapezoid(p, 0.37), 1e-8);
}

TEST(SpeedProfile, ReversalCrossesZeroAtTheQuarterPeriodsAndIntegratesExactly) {
  // +1000 rpm -> 0 at P/4 -> -1000 rpm at P/2 -> 0 at 3P/4 -> +1000 rpm at P: omega = s cos(2 pi t
  // / P).
  const double s = 1000.0 * kRpm, P = 2.0;
  const SpeedProfile p(SpeedReversal{s, 0.0, P});
  EXPECT_NEAR(p.speed(0.0), s, 1e-12);
  EXPECT_NEAR(p.speed(P / 2), -s, 1e-12);
  EXPECT_NEAR(p.speed(P), s, 1e-12);
  for (double zero : {P / 4, 3 * P / 4}) {
    EXPECT_NEAR(p.speed(zero), 0.0, 1e-12 * s) << zero;
    EXPECT_LT(p.speed(zero - 1e-3) * p.speed(zero + 1e-3), 0.0) << "the sign changes at " << zero;
  }
  EXPECT_GT(p.speed(P / 4 - 1e-3), 0.0);
  EXPECT_LT(p.speed(P / 4 + 1e-3), 0.0);
  for (double t : {0.1, 0.5, 0.77, 1.0, 1.3, 1.5, 1.99}) {
    EXPECT_NEAR(p.speed(t), s * std::cos(kTwoPi * t / P), 1e-9);
    EXPECT_NEAR(p.angle(t), s * P * std::sin(kTwoPi * t / P) / kTwoPi, 1e-10) << t;
    EXPECT_NEAR(p.angle(t), trapezoid(p, t), 1e-7) << t;
  }
  // The angle peaks where the speed is zero (P/4), and a whole cycle returns to the start.
  EXPECT_NEAR(p.angle(P / 4), s * P / kTwoPi, 1e-10);
  EXPECT_NEAR(p.angle(P), 0.0, 1e-10);
  EXPECT_NEAR(p.angle(P + 0.5), 0.5 * s, 1e-10);  // then held at +s
}

TEST(SpeedProfile, DelayedReversalIsContinuousAtItsEnds) {
  const double s = 50.0, t0 = 0.3, P = 0.8;
  const SpeedProfile p(SpeedReversal{s, t0, P});
  EXPECT_NEAR(p.angle(t0), s * t0, 1e-12);
  EXPECT_NEAR(p.angle(t0 + P), s * t0, 1e-12);  // a whole cosine cycle adds nothing
  for (double knot : {t0, t0 + P / 2, t0 + P}) {
    const double eps = 1e-6;
    EXPECT_NEAR(p.speed(knot - eps), p.speed(knot + eps), 1e-6 * s) << knot;
    EXPECT_NEAR((p.angle(knot + eps) - p.angle(knot - eps)) / (2 * eps), p.speed(knot), 1e-5 * s)
        << knot;
  }
}

TEST(SpeedProfile, RefusesBadInputNamingTheField) {
  expectRefusal([] { SpeedProfile p(std::nan("")); }, "speed");
  expectRefusal([] { SpeedProfile p(2e5); }, "speed");
  expectRefusal([] { SpeedProfile p(SpeedRamp{0.0, 100.0, 1.0, 1.0}); }, "speed_ramp.end");
  expectRefusal([] { SpeedProfile p(SpeedRamp{0.0, INFINITY, 0.0, 1.0}); }, "speed_ramp.to");
  expectRefusal([] { SpeedProfile p(SpeedRamp{0.0, 1.0, std::nan(""), 1.0}); }, "speed_ramp.start");
  expectRefusal(
      [] {
        SpeedProfile p(SpeedSteps{0.0, {{0.0, 1.0}}, 0.0});
      },
      "speed_steps.ramp_duration");
  expectRefusal(
      [] {
        SpeedProfile p(SpeedSteps{0.0, {{0.0, 1.0}, {0.04, 2.0}}, 0.05});
      },
      "speed_steps.steps[1].time");
  expectRefusal(
      [] {
        SpeedProfile p(SpeedSteps{0.0, {{0.0, 1.0}, {0.5, NAN}}, 0.05});
      },
      "speed_steps.steps[1].speed");
  expectRefusal([] { SpeedProfile p(SpeedReversal{-1.0, 0.0, 1.0}); }, "speed_reversal.speed");
  expectRefusal([] { SpeedProfile p(SpeedReversal{1.0, 0.0, 0.0}); }, "speed_reversal.period");
  expectRefusal([] { SpeedProfile p(SpeedReversal{1.0, 1e300, 1.0}); }, "speed_reversal.start");
}

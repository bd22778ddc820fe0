// PhaseSource: the nominal angle from its origin, a reading anchoring the phase (the offset in the
// mesh phase, not in the encoder angle), unwrapping across an encoder's wrap, a differentiated
// speed, an encoder jump refused with nothing changed, the time-out falling back to the nominal
// speed from the angle reached, and a gear slip reported once.
#include <gtest/gtest.h>

#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

constexpr int kZp = 20, kZg = 40;
Stamp at(double seconds) { return test::stampAt(seconds); }

struct Fixture {
  PipelineOptions options = [] {
    PipelineOptions o;
    o.pinion_speed_rpm = 600.0;  // 20 pi rad/s
    o.mesh_phase_offset = 0.25;
    o.motion_timeout = 0.1;
    return o;
  }();
  PhaseSource phase{options, kZp, kZg};
  const PhaseCounters& counters = phase.counters();
  /// Unwraps and anchors a reading; returns whether it continued the last one.
  bool read(double t, double pinion, std::optional<double> velocity = std::nullopt,
            std::optional<double> gear = std::nullopt) {
    bool continuous = false;
    PhaseSource::Reading r = phase.unwrap(at(t), MotionInput{pinion, velocity, gear}, continuous);
    phase.checkGearRatio(r);
    phase.anchorTo(r);
    return continuous;
  }
};

const double kOffsetAngle = 0.25 * kTwoPi / kZp;  // [rad] the mesh phase offset as a pinion angle

}  // namespace

TEST(PhaseSource, NominalAngleCountsFromTheOrigin) {
  Fixture f;
  EXPECT_STREQ(f.phase.name(), "nominal");
  EXPECT_EQ(f.phase.pinionAngle(at(1.0)), 0.0);  // no origin yet
  f.phase.setOrigin(at(1.0));
  EXPECT_NEAR(f.phase.pinionAngle(at(1.5)), 0.5 * 20.0 * kPi, 1e-12);
  EXPECT_EQ(f.phase.encoderPinionAngle(at(1.5)), f.phase.pinionAngle(at(1.5)));
  EXPECT_NEAR(f.phase.stiffnessAngle(at(1.25), at(1.0)), 0.25 * 20.0 * kPi, 1e-12);
  EXPECT_FALSE(f.phase.encoderSilence(at(2.0)));
}

TEST(PhaseSource, AReadingAnchorsThePhaseWithTheOffset) {
  Fixture f;
  EXPECT_FALSE(f.read(0.0, 0.3, 10.0));
  EXPECT_STREQ(f.phase.name(), "encoders");
  EXPECT_TRUE(f.phase.encodersDrive());
  EXPECT_NEAR(f.phase.encoderPinionAngle(at(0.01)), 0.3 + 0.1, 1e-12);  // extrapolated at 10 rad/s
  EXPECT_NEAR(f.phase.pinionAngle(at(0.01)), 0.4 + kOffsetAngle, 1e-12);
  EXPECT_NEAR(f.phase.meshPhase(0.0), 0.25, 1e-15);
  EXPECT_NEAR(*f.phase.encoderSilence(at(0.05)), 0.05, 1e-12);
}

TEST(PhaseSource, ReadingsUnwrapAcrossTheEncodersWrapAndDifferentiate) {
  Fixture f;
  EXPECT_FALSE(f.read(0.0, kPi - 0.05));
  // 0.1 rad further on the wrapped encoder: -pi + 0.05, unwrapped to pi + 0.05.
  EXPECT_TRUE(f.read(0.01, -kPi + 0.05));
  EXPECT_NEAR(f.phase.anchor()->angle - kOffsetAngle, kPi + 0.05, 1e-12);
  EXPECT_NEAR(f.phase.anchor()->speed, 0.1 / 0.01, 1e-9);  // backward difference
}

TEST(PhaseSource, AnEncoderJumpIsRefusedWithNothingChanged) {
  Fixture f;
  f.read(0.0, 0.0, 10.0);
  bool continuous = false;
  // 3 rad in 10 us: 3e5 rad/s, beyond 1e5 rpm.
  EXPECT_THROW(f.phase.unwrap(at(1e-5), MotionInput{3.0, std::nullopt, std::nullopt}, continuous),
               InvalidInput);
  EXPECT_NEAR(f.phase.anchor()->angle, kOffsetAngle, 1e-15);
  EXPECT_NEAR(f.phase.anchor()->speed, 10.0, 1e-15);
}

TEST(PhaseSource, TheTimeOutFallsBackToTheNominalSpeedFromTheAngleReached) {
  Fixture f;
  f.read(0.0, 0.0, 10.0);
  EXPECT_FALSE(f.phase.encodersTimedOut(at(0.1)));  // exactly ~motion_timeout: still driving
  const std::optional<Stamp> out = f.phase.encodersTimedOut(at(0.25));
  ASSERT_TRUE(out);
  EXPECT_TRUE(*out == at(0.1));
  EXPECT_EQ(f.counters.motion_timeouts, 1u);
  const double reached = f.phase.pinionAngle(*out);
  f.phase.fallBackToNominal(*out);
  EXPECT_STREQ(f.phase.name(), "nominal (encoders timed out)");
  EXPECT_NEAR(f.phase.pinionAngle(at(0.2)), reached + 0.1 * 20.0 * kPi, 1e-9);
  EXPECT_FALSE(f.phase.encoderSilence(at(0.3)));
  // The next reading starts afresh (no unwrapping against the stale one).
  EXPECT_FALSE(f.read(0.3, 1.0, 10.0));
  f.phase.reset();
  EXPECT_STREQ(f.phase.name(), "nominal");
}

TEST(PhaseSource, AGearSlipIsReportedOnce) {
  Fixture f;
  f.read(0.0, 0.0, 10.0, 0.0);
  f.read(0.001, 0.01, 10.0, -0.005);  // on the ratio: -(20/40) x 0.01
  EXPECT_EQ(f.counters.gear_ratio_mismatches, 0u);
  f.read(0.002, 0.02, 10.0, -0.01 + 0.05);  // slipped by 0.05 rad
  EXPECT_EQ(f.counters.gear_ratio_mismatches, 1u);
  f.read(0.003, 0.03, 10.0, -0.015 + 0.05);  // on the ratio from the slipped reference
  EXPECT_EQ(f.counters.gear_ratio_mismatches, 1u);
}

// Involute geometry against textbook relations (ISO 21771 / Niemann-Winter) and the mesh phase.
#include <gtest/gtest.h>

#include "drivetrain_stiffness/core/validation.hpp"
#include "gear_fixtures.hpp"

using namespace drivetrain_stiffness;

namespace {
// Textbook transverse contact ratio of external spur gears (Niemann & Winter, Maschinenelemente II;
// Shigley): eps = [sqrt(ra1^2 - rb1^2) + sqrt(ra2^2 - rb2^2) - a_w sin(alpha_w)] / (pi m
// cos(alpha)).
double textbookContactRatio(const SpurGearGeometry& g) {
  const double m = g.spec().module, a = g.spec().pressure_angle;
  return (std::sqrt(g.tipRadius(0) * g.tipRadius(0) - g.baseRadius(0) * g.baseRadius(0)) +
          std::sqrt(g.tipRadius(1) * g.tipRadius(1) - g.baseRadius(1) * g.baseRadius(1)) -
          g.centerDistance() * std::sin(g.operatingPressureAngle())) /
         (M_PI * m * std::cos(a));
}
}  // namespace

TEST(GearGeometry, SeedPairRadiiAndContactRatio) {
  const SpurGearGeometry g(test::seedPair());
  EXPECT_NEAR(g.referenceRadius(0), 6e-3, 1e-15);
  EXPECT_NEAR(g.baseRadius(0), 6e-3 * std::cos(20.0 * M_PI / 180), 1e-15);
  EXPECT_NEAR(g.tipRadius(0), 6.6e-3, 1e-15);            // r + m h_a
  EXPECT_NEAR(g.rootRadius(1), 12e-3 - 0.75e-3, 1e-15);  // r - 1.25 m
  EXPECT_NEAR(g.centerDistance(), 18e-3, 1e-15);
  EXPECT_NEAR(g.contactRatio(), textbookContactRatio(g), 1e-12);
  EXPECT_NEAR(g.contactRatio(), 1.635,
              0.001);  // 20/40, 20 deg, full depth: 1.635 (textbook formula, evaluated by hand)
  EXPECT_NEAR(g.backlash(), 0.0, 1e-15);
  EXPECT_NEAR(g.backFlankPhaseOffset(), 0.5, 1e-12);  // unshifted teeth: thickness = half the pitch
}

// Shifted gears in a tight mesh: inv(alpha_w) = inv(alpha) + 2 tan(alpha)(x1+x2)/(z1+z2) must close
// the backlash exactly (tooth thicknesses on the operating circle add up to the pitch).
TEST(GearGeometry, ProfileShiftTightMeshHasNoBacklash) {
  GearPairSpec s = test::seedPair();
  s.teeth = {14, 33};
  s.profile_shift = {0.4, 0.25};
  const SpurGearGeometry g(s);
  EXPECT_NEAR(g.backlash(), 0.0, 1e-12);
  EXPECT_GT(g.centerDistance(), 0.5 * s.module * 47);
  EXPECT_NEAR(involute(g.operatingPressureAngle()),
              involute(s.pressure_angle) + 2 * std::tan(s.pressure_angle) * 0.65 / 47, 1e-14);
  EXPECT_NEAR(g.contactRatio(), textbookContactRatio(g), 1e-12);
  EXPECT_GT(g.tipShortening(), 0.0);  // x1 + x2 exceeds the centre-distance increase
}

// A larger centre distance opens backlash j_t ~ 2 da tan(alpha_w) (circumferential, small da).
TEST(GearGeometry, CentreDistanceOpensBacklash) {
  GearPairSpec s = test::seedPair();
  s.center_distance = 18.02e-3;
  const SpurGearGeometry g(s);
  EXPECT_NEAR(g.backlash() / (2 * 0.02e-3 * std::tan(g.operatingPressureAngle())), 1.0, 0.01);
  EXPECT_LT(g.contactRatio(), SpurGearGeometry(test::seedPair()).contactRatio());
}

TEST(GearGeometry, PairsInContactFollowTheContactRatio) {
  const SpurGearGeometry g(test::seedPair());
  const double eps = g.contactRatio();
  std::array<double, 3> s;
  int double_drive = 0, double_back = 0;
  const int n = 10000;
  for (int i = 0; i < n; ++i) {
    const double phi = (i + 0.5) / n;
    const int d = g.drivePairs(phi, s), b = g.backPairs(phi, s);
    EXPECT_TRUE(d == 1 || d == 2);
    EXPECT_TRUE(b == 1 || b == 2);
    double_drive += d == 2;
    double_back += b == 2;
    EXPECT_EQ(d == 2, phi <= eps - 1.0);  // seed 000 eq 2 switching
  }
  EXPECT_NEAR(double_drive / double(n), eps - 1.0, 2.0 / n);
  EXPECT_NEAR(double_back / double(n), eps - 1.0, 2.0 / n);
  EXPECT_NEAR(g.phase(2 * M_PI / 20 * 3.25), 0.25, 1e-12);  // periodic in the angular pitch
  EXPECT_NEAR(g.phase(-2 * M_PI / 20 * 0.25), 0.75, 1e-12);
}

TEST(GearGeometry, RejectsImpossibleGearsNamingTheField) {
  auto expectMessage = [](GearPairSpec s, const std::string& text) {
    try {
      SpurGearGeometry g(s);
      FAIL() << "accepted: " << text;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  GearPairSpec s = test::seedPair();
  s.teeth = {12, 40};
  expectMessage(s, "gears.teeth[0] = 12 with gears.profile_shift[0] = 0: undercut");
  s.profile_shift = {0.3, 0.0};
  EXPECT_NO_THROW(SpurGearGeometry{s});  // 1 - 12 sin^2(20)/2 = 0.298
  s = test::seedPair();
  s.center_distance = 17.9e-3;
  expectMessage(s, "gears.center_distance = 0.0179");
  s = test::seedPair();
  s.center_distance = 18.6e-3;
  expectMessage(s, "contact ratio");
  s = test::seedPair();
  s.module = NAN;
  expectMessage(s, "gears.module = nan");
  s = test::seedPair();
  s.teeth = {10, 40};
  s.profile_shift = {1.2, 0.0};
  expectMessage(s, "pointed teeth");
  s = test::seedPair();
  s.pressure_angle = 50 * M_PI / 180;
  expectMessage(s, "gears.pressure_angle_deg = 50");
}

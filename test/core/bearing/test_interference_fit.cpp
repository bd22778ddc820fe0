// Lame interference fits against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "drivetrain_stiffness/core/bearing/interference_fit.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

using namespace drivetrain_stiffness;

namespace {
const ElasticMaterial kSteel{207e9, 0.3};

InnerRingFit innerFit(double interference, double shaft_bore) {
  return {interference, 65e-3, 71.4e-3, shaft_bore, kSteel, kSteel};
}
}  // namespace

// Solid shaft of the ring's material: the raceway grows by I d / d_i (bearing.md section 3,
// derived from Lame; SKF's "clearance reduction caused by interference fits" has the same d/d_i
// factor).
TEST(InterferenceFit, SolidShaftSameMaterialClosedForm) {
  const double interference = 20e-6;
  const FitResult r = innerRingFit(innerFit(interference, 0.0));
  EXPECT_NEAR(r.raceway_change / (interference * 65e-3 / 71.4e-3), 1.0, 1e-12);
}

// Infinitely thick housing of the ring's material: the raceway shrinks by I d_o / D.
TEST(InterferenceFit, ThickHousingSameMaterialClosedForm) {
  const double interference = 15e-6;
  const OuterRingFit fit{interference, 100e-3, 93.6e-3, INFINITY, kSteel, kSteel};
  EXPECT_NEAR(outerRingFit(fit).raceway_change / (interference * 93.6e-3 / 100e-3), 1.0, 1e-12);
}

// Shigley's Mechanical Engineering Design (10th ed.) eq 3-57, both members of one material:
//   p = E delta / (2 b^3) [(c^2 - b^2)(b^2 - a^2) / (c^2 - a^2)], delta the radial interference,
//   a the bore of the inner member, b the fit radius, c the outside radius of the outer member.
TEST(InterferenceFit, PressureMatchesShigleyEqualMaterials) {
  const double a = 20e-3 / 2, b = 65e-3 / 2, c = 71.4e-3 / 2, interference = 30e-6;
  const double p_shigley = kSteel.youngs_modulus * (interference / 2.0) / (2.0 * b * b * b) *
                           ((c * c - b * b) * (b * b - a * a) / (c * c - a * a));
  EXPECT_NEAR(innerRingFit(innerFit(interference, 2.0 * a)).contact_pressure / p_shigley, 1.0,
              1e-12);
}

TEST(InterferenceFit, LinearInInterferenceAndSofterWithHollowShaft) {
  const double solid = innerRingFit(innerFit(10e-6, 0.0)).raceway_change;
  EXPECT_NEAR(innerRingFit(innerFit(20e-6, 0.0)).raceway_change, 2.0 * solid, 1e-18);
  EXPECT_LT(innerRingFit(innerFit(10e-6, 40e-3)).raceway_change, solid);
  EXPECT_EQ(innerRingFit(innerFit(0.0, 0.0)).raceway_change, 0.0);
  const OuterRingFit thick{10e-6, 100e-3, 93.6e-3, INFINITY, kSteel, kSteel};
  OuterRingFit thin = thick;
  thin.housing_outside_diameter = 110e-3;
  EXPECT_LT(outerRingFit(thin).raceway_change, outerRingFit(thick).raceway_change);
}

TEST(InterferenceFit, RejectsImpossibleGeometryNamingTheField) {
  auto expectMessage = [](auto&& fn, const std::string& text) {
    try {
      fn();
      FAIL() << "accepted: " << text;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  expectMessage([] { innerRingFit(innerFit(-1e-6, 0.0)); }, "inner_interference = -1e-06");
  expectMessage([] { innerRingFit(innerFit(1e-6, 70e-3)); }, "shaft_bore_diameter = 0.07");
  expectMessage(
      [] {
        innerRingFit({1e-6, 72e-3, 71.4e-3, 0.0, kSteel, kSteel});
      },
      "bore_diameter = 0.072");
  expectMessage(
      [] {
        outerRingFit({1e-6, 100e-3, 93.6e-3, 99e-3, kSteel, kSteel});
      },
      "outside_diameter = 0.1");
  expectMessage(
      [] {
        outerRingFit({1e-6, 100e-3, 93.6e-3, NAN, kSteel, kSteel});
      },
      "housing_outside_diameter = nan");
}

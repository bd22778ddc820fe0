// Configuration files: the shipped ones load; bad ones fail with the file, key and value named.
#include <gtest/gtest.h>

#include <fstream>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/hertz_contact.hpp"
#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

using namespace drivetrain_stiffness;

namespace {
const std::string kSource = DRIVETRAIN_SOURCE_DIR;

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

void expectLoadError(const std::string& text, const std::string& fragment) {
  const std::string path = writeTemp("bad_bearing.yaml", text);
  try {
    loadBearingFile(path);
    FAIL() << "accepted: " << text;
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

const char* kGood = R"(bearing:
  balls: 19
  ball_diameter: 11.1e-3
  pitch_diameter: 82.5e-3
  inner_groove_conformity: 0.515
  outer_groove_conformity: 0.515
  contact_angle_deg: 25
  youngs_modulus: 207e9
  poisson_ratio: 0.29
)";
}  // namespace

TEST(YamlConfig, ShippedFilesLoad) {
  const BearingSupportConfig b = loadBearingFile(kSource + "/config/bearings/7013ac.yaml");
  EXPECT_EQ(b.spec.balls, 19);
  EXPECT_DOUBLE_EQ(b.spec.ball_diameter, 11.1e-3);
  EXPECT_NEAR(*b.spec.contact_angle, 25.0 * M_PI / 180.0, 1e-15);
  const RigConfig rig = loadRigFile(kSource + "/config/gearboxes/seed_servo.yaml");
  ASSERT_EQ(rig.bearings.size(), 2u);
  EXPECT_EQ(rig.bearings[0].name, "pinion_bearing");
  EXPECT_EQ(rig.bearings[1].shaft, 1);
  EXPECT_DOUBLE_EQ(rig.bearings[0].radial_preload, 1000.0);   // entry overrides the bearing file
  EXPECT_DOUBLE_EQ(rig.bearings[0].interference.inner, 5e-6);  // inherited from the bearing file
  // Seed 000 Table 1: r_b = m z cos(20 deg) / 2 = 0.6 mm * 20 * 0.93969 / 2 = 5.638 mm.
  EXPECT_NEAR(baseRadius(rig.gears, 0), 5.6382e-3, 1e-7);
}

TEST(YamlConfig, GoodMinimalBearing) {
  const BearingSupportConfig b = loadBearingFile(writeTemp("good.yaml", kGood));
  EXPECT_EQ(b.arrangement, Arrangement::kSingle);
  EXPECT_EQ(b.tilt, TiltCondition::kConstrained);
  EXPECT_FALSE(b.spec.fit.has_value());
}

TEST(YamlConfig, ErrorsNameTheKeyAndValue) {
  std::string text = kGood;
  expectLoadError(text + "  colour: blue\n", "bearing.colour: unknown key");
  expectLoadError(std::string(kGood).replace(text.find("19"), 2, "abc"), "bearing.balls = 'abc': not a number");
  expectLoadError(std::string(kGood).replace(text.find("19"), 2, "2.5"), "bearing.balls = 2.5: must be an integer");
  expectLoadError(std::string(kGood).replace(text.find("11.1e-3"), 7, "-11.1e-3"), "ball_diameter = -0.0111");
  expectLoadError(std::string(kGood).replace(text.find("11.1e-3"), 7, ".nan"), "ball_diameter = nan");
  expectLoadError(text + "  diametral_clearance: 1e-5\n", "not both");
  expectLoadError(text + "  arrangement: tandem\n", "bearing.arrangement = 'tandem'");
  expectLoadError(text + "  inner_interference: 5e-6\n", "needs the fit geometry");
  expectLoadError("bearing: [1, 2\n", "YAML syntax error at line");
  expectLoadError("gears: {}\n", "needs a top-level 'bearing:' block");
  std::string no_balls = kGood;
  no_balls.erase(no_balls.find("  balls: 19\n"), 12);
  expectLoadError(no_balls, "bearing.balls: required key is missing");
  EXPECT_THROW(loadBearingFile("/nonexistent/x.yaml"), InvalidInput);
}

TEST(YamlConfig, RigErrors) {
  const std::string rig = R"(gears: {module: 0.6e-3, pressure_angle_deg: 20, teeth: [20, 40]}
bearings:
  - {name: a, file: )" + kSource + R"(/config/bearings/7013ac.yaml}
  - {name: a, file: )" + kSource + R"(/config/bearings/7013ac.yaml}
)";
  std::string path = writeTemp("rig.yaml", rig);
  try {
    loadRigFile(path);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("duplicate name"), std::string::npos) << e.what();
  }
  const std::string bad_gear = "gears: {module: 0.6e-3, pressure_angle_deg: 60, teeth: [20, 40]}\nbearings: []\n";
  try {
    loadRigFile(writeTemp("rig2.yaml", bad_gear));
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("gears.pressure_angle_deg = 60"), std::string::npos) << e.what();
  }
}

// Each enum's names come from one table: every name parses back to its value, and a wrong name is
// refused with the field and the full list of accepted names (the format the CLI tests match).
TEST(EnumNames, RoundTripAndRefusalListsEveryName) {
  for (Fidelity f : {Fidelity::kFull, Fidelity::kQuasiStatic, Fidelity::kLinearModal}) {
    EXPECT_EQ(parseFidelity("fidelity", toString(f)), f);
  }
  for (Arrangement a : {Arrangement::kSingle, Arrangement::kBackToBack, Arrangement::kFaceToFace}) {
    EXPECT_EQ(parseArrangement("arrangement", toString(a)), a);
  }
  try {
    parseArrangement("bearings[0].arrangement", "tandem");
    FAIL() << "accepted 'tandem'";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "bearings[0].arrangement = 'tandem': must be 'single', 'back_to_back' or 'face_to_face'");
  }
  try {
    parseEllipticityMethod("ellipticity", "x");
    FAIL() << "accepted 'x'";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "ellipticity = 'x': must be 'exact' or 'hamrock_dowson'");
  }
}

// Configuration files: the shipped ones load; bad ones fail with the file, key and value named.
#include <gtest/gtest.h>

#include <fstream>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/bearing/hertz_contact.hpp"
#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
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
  EXPECT_DOUBLE_EQ(rig.bearings[0].radial_preload, 1000.0);    // entry overrides the bearing file
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
  expectLoadError(std::string(kGood).replace(text.find("19"), 2, "abc"),
                  "bearing.balls = 'abc': not a number");
  expectLoadError(std::string(kGood).replace(text.find("19"), 2, "2.5"),
                  "bearing.balls = 2.5: must be an integer");
  expectLoadError(std::string(kGood).replace(text.find("11.1e-3"), 7, "-11.1e-3"),
                  "ball_diameter = -0.0111");
  expectLoadError(std::string(kGood).replace(text.find("11.1e-3"), 7, ".nan"),
                  "ball_diameter = nan");
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
  - {name: a, file: )" + kSource +
                          R"(/config/bearings/7013ac.yaml}
  - {name: a, file: )" + kSource +
                          R"(/config/bearings/7013ac.yaml}
)";
  std::string path = writeTemp("rig.yaml", rig);
  try {
    loadRigFile(path);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("duplicate name"), std::string::npos) << e.what();
  }
  const std::string bad_gear =
      "gears: {module: 0.6e-3, pressure_angle_deg: 60, teeth: [20, 40]}\nbearings: []\n";
  try {
    loadRigFile(writeTemp("rig2.yaml", bad_gear));
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("gears.pressure_angle_deg = 60"), std::string::npos)
        << e.what();
  }
}

// Hostile files found by the fuzz harness (test/fuzz/): every one is refused with InvalidInput (or
// UnreachableLoad) whose message begins with the file and names the key; none lets another
// exception type escape.
namespace {

const char* kGears =
    "gears: {module: 0.6e-3, pressure_angle_deg: 20, teeth: [20, 40], face_width: 6.5e-3}\n";

// The refusal's message, or a failure if the load is accepted or something else is thrown.
template <typename Exception = InvalidInput, typename Load>
std::string refusal(Load load, const std::string& path) {
  try {
    load(path);
  } catch (const Exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted " << path;
  return {};
}

void expectNames(const std::string& message, const std::string& path, const std::string& fragment) {
  EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
  EXPECT_NE(message.find(fragment), std::string::npos) << message;
}

}  // namespace

TEST(YamlConfig, KeysThatAreNotNamesAreRefused) {
  // A sequence or mapping as a key is refused by name, not left to escape as
  // YAML::TypedBadConversion.
  std::string path = writeTemp("seq_key.yaml", std::string(kGood) + "  [a, b]: 1\n");
  expectNames(refusal(loadBearingFile, path), path, "bearing: key ");
  path = writeTemp("seq_top.yaml", std::string(kGears) + "? [a]\n: 1\nbearings: []\n");
  expectNames(refusal(loadRigFile, path), path, "key ");
  path = writeTemp("file_seq.yaml", std::string(kGears) + "bearings:\n  - {name: a, file: [x]}\n");
  expectNames(refusal(loadRigFile, path), path, "bearings[0].file: must be a string");
  // A NUL in a key is escaped: as a C string it would cut the message short before it named
  // anything.
  path = writeTemp("nul_key.yaml", std::string(kGears) + "\"a\\0b\": 1\nbearings: []\n");
  expectNames(refusal(loadRigFile, path), path, "'a\\x00b': unknown top-level key");
}

TEST(YamlConfig, BlockRefusalsNameTheFile) {
  // Refusals in mesh:, anti_backlash:, dynamics: and of the bearing's name name the file too.
  std::string path = writeTemp("mesh.yaml", std::string(kGears) + "mesh: {samples: 8}\n");
  expectNames(refusal(loadGearFile, path), path, "mesh.samples = 8");
  path = writeTemp("mesh_model.yaml", std::string(kGears) + "mesh: {model: [1]}\n");
  expectNames(refusal(loadGearFile, path), path, "mesh.model: must be a string");
  path = writeTemp(
      "ab.yaml", std::string(kGears) + "anti_backlash: {spring_stiffness: 0, preload_torque: 1}\n");
  expectNames(refusal(loadGearFile, path), path, "anti_backlash.spring_stiffness = 0");
  path = writeTemp(
      "dyn.yaml",
      std::string(kGears) +
          "dynamics: {pinion_mass: 0, gear_mass: 1, pinion_inertia: 1, gear_inertia: 1}\n");
  expectNames(refusal(loadGearFile, path), path, "dynamics.pinion_mass = 0");
  path = writeTemp("name.yaml", std::string(kGood) + "  name: [1]\n");
  expectNames(refusal(loadBearingFile, path), path, "bearing.name: must be a string");
}

TEST(YamlConfig, ContactAngleIsRefusedInDegrees) {
  // Named as the file names it, in degrees, not as "contact_angle = 1.745" (radians, a name the
  // file does not have).
  const std::string path =
      writeTemp("angle.yaml", std::string(kGood).replace(std::string(kGood).find("25"), 2, "100"));
  expectNames(refusal(loadBearingFile, path), path, "bearing.contact_angle_deg = 100");
}

TEST(YamlConfig, ReferencedFileRefusalsNameTheEntry) {
  // A missing file, a directory (not left to escape as std::ios_base::failure) and a file that is
  // not a bearing file: each names the entry's file: key, then the file.
  for (const std::string& name :
       {std::string("no_such.yaml"), testing::TempDir(), writeTemp("scalar.yaml", "just text\n"),
        writeTemp("scalar_bearing.yaml", "bearing: 7\n")}) {
    const std::string path = writeTemp(
        "ref.yaml", std::string(kGears) + "bearings:\n  - {name: a, file: '" + name + "'}\n");
    expectNames(refusal(loadRigFile, path), path, "bearings[0].file = '" + name + "': ");
  }
}

TEST(YamlConfig, UnreachablePreloadNamesFileAndKey) {
  // A duplex preload no geometry carries is refused naming the file and its key, not as
  // "axial_load = ..." alone.
  const std::string path = writeTemp(
      "pair.yaml", std::string(kGood) + "  arrangement: back_to_back\n  axial_preload: 1e300\n");
  expectNames(refusal<UnreachableLoad>(loadBearingFile, path), path,
              "bearing: axial_preload = 1e+300");
}

TEST(YamlConfig, AbsurdMagnitudesAreRefusedNotNaN) {
  // Each passed every sign check and then overflowed into a NaN stiffness (fuzz findings).
  const std::string bearing_file = kSource + "/config/bearings/servo_7000ac.yaml";
  const std::string rig =
      std::string(kGears) + "bearings:\n  - {name: a, file: '" + bearing_file + "'}\n";
  struct Case {
    std::string from, to, named;
  };
  const Case cases[] = {
      {"face_width: 6.5e-3", "face_width: 1e308", "gears.face_width = 1e+308"},
      {"module: 0.6e-3", "module: 1e308", "gears.module = 1e+308"},
      {"teeth", "youngs_modulus: 1e308, teeth", "gears.youngs_modulus = 1e+308"},
      {"bearings:", "anti_backlash: {spring_stiffness: 1e308, preload_torque: 1}\nbearings:",
       "anti_backlash.spring_stiffness = 1e+308"},
      {"bearings:", "anti_backlash: {spring_stiffness: 1e7, preload_torque: 1e308}\nbearings:",
       "anti_backlash.preload_torque = 1e+308"},
      {"name: a,", "name: a, pitch_diameter: 1e308,", "pitch_diameter = 1e+308"},
      {"name: a,", "name: a, youngs_modulus: 1e308,", "youngs_modulus = 1e+308"},
      {"name: a,", "name: a, youngs_modulus: 4.9e-324,", "youngs_modulus = 4.940656458e-324"},
      {"name: a,", "name: a, shaft_youngs_modulus: 1e308,", "youngs_modulus = 1e+308"},
  };
  for (const Case& c : cases) {
    const std::string path =
        writeTemp("absurd.yaml", std::string(rig).replace(rig.find(c.from), c.from.size(), c.to));
    expectNames(refusal(loadRigFile, path), path, c.named);
  }
}

TEST(YamlConfig, ADirectoryIsRefusedBeforeYamlCppReadsIt) {
  // yaml-cpp's reader throws std::ios_base::failure on a directory's first read and leaks its
  // prefetch buffer doing so (LeakSanitizer in scripts/test --sanitize): refused up front instead.
  const std::string dir = testing::TempDir();
  try {
    loadBearingFile(dir);
    FAIL() << "accepted a directory";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(dir + ": is a directory"), std::string::npos) << e.what();
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
    EXPECT_STREQ(
        e.what(),
        "bearings[0].arrangement = 'tandem': must be 'single', 'back_to_back' or 'face_to_face'");
  }
  try {
    parseEllipticityMethod("ellipticity", "x");
    FAIL() << "accepted 'x'";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "ellipticity = 'x': must be 'exact' or 'hamrock_dowson'");
  }
}

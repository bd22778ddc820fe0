// drivetrain_replay --calibrate's gearbox YAML (src/tools/replay/calibrated_gearbox.hpp): written
// from a calibration estimate, reloaded with loadRigFile as the node loads ~gearbox_config, the
// calibrated values round-trip exactly and the rest of the rig is unchanged; relative bearing
// `file:` references still resolve from another directory; a config without a calibration block and
// an estimate that no window updated are refused and nothing is written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "replay/calibrated_gearbox.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

namespace fs = std::filesystem;

const std::string kSource = DRIVETRAIN_SOURCE_DIR;
const std::string kConfig = kSource + "/test/data/calibration_servo.yaml";

CalibrationEstimate fitted() {
  CalibrationEstimate e;
  // Values with all 17 digits, so that a lossy number format would show.
  e.value << 0.83123456789012345, 1.2345678901234567, 0.67890123456789012, 0.76543210987654321,
      3.2109876543210987e-7;
  e.std << 0.051234567890123456, 0.11, 0.29, 0.031, 1.7e-8;
  e.prior_std << 0.2, 0.3, 0.3, 0.2, 1e-6;
  e.identified = {true, true, false, true, true};
  e.windows = 12;
  e.baseline_windows = 3;
  e.updates = 7;
  e.gated = 1;
  e.not_excited = 1;
  e.outcome = WindowOutcome::kUpdated;
  return e;
}

CalibrationProvenance provenance() {
  return {"/data/rig_run.bag", "2026-01-01T00:00:00Z to 2026-01-01T00:00:02Z", "now", "ok"};
}

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / ("calibrated_gearbox_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void expectPrior(const CalibrationPrior& prior, const CalibrationEstimate& e, int i,
                 const CalibrationPrior& drawing) {
  EXPECT_EQ(prior.mean, e.value[i]) << calibrationName(i);
  // The drawing's spread, for a bearing scale kept in compliance (the filter's c = 1/s: std(c) =
  // std(s) / s^2), so read at the calibrated mean s' as std(s) (s' / s)^2.
  const bool bearing = i == kPinionBearingScale || i == kGearBearingScale;
  const double ratio = e.value[i] / drawing.mean;
  const double reference = bearing ? drawing.reference() * ratio * ratio : drawing.reference();
  if (bearing) {
    const double in_compliance = drawing.reference() / (drawing.mean * drawing.mean);
    EXPECT_NEAR(reference / (e.value[i] * e.value[i]) / in_compliance, 1.0, 1e-14)
        << calibrationName(i) << ": the same spread in compliance";
  }
  // Identified: the posterior std; not: the drawing's spread (the file holds no covariance).
  EXPECT_EQ(prior.std, e.identified[static_cast<std::size_t>(i)] ? e.std[i] : reference)
      << calibrationName(i);
  // The drawing's spread stays what `identified` and the drift are judged against.
  EXPECT_EQ(prior.reference_std, reference) << calibrationName(i) << ": written out";
}

TEST(CalibratedGearbox, RoundTripsThroughLoadRigFile) {
  const fs::path out =
      scratch("round_trip") / "sub" / "calibrated.yaml";  // another directory, created
  const CalibrationEstimate e = fitted();
  writeCalibratedGearbox(kConfig, e, out.string(), provenance());
  const RigConfig before = loadRigFile(kConfig);
  const RigConfig after = loadRigFile(out.string());

  // The calibrated values, exactly.
  EXPECT_EQ(after.mesh_stiffness_scale, e.value[kMeshScale]);
  ASSERT_EQ(after.bearings.size(), before.bearings.size());
  for (const BearingSupportConfig& b : after.bearings) {
    EXPECT_EQ(b.stiffness_scale, e.value[b.shaft == 0 ? kPinionBearingScale : kGearBearingScale])
        << b.name;
  }
  EXPECT_EQ(after.anti_backlash.preload_torque, e.value[kPreloadTorque]);
  ASSERT_TRUE(after.calibration.present);
  const CalibrationConfig& c = before.calibration;
  expectPrior(after.calibration.mesh_stiffness_scale, e, kMeshScale, c.mesh_stiffness_scale);
  expectPrior(after.calibration.pinion_bearing_scale, e, kPinionBearingScale,
              c.pinion_bearing_scale);
  expectPrior(after.calibration.gear_bearing_scale, e, kGearBearingScale, c.gear_bearing_scale);
  expectPrior(after.calibration.preload_torque, e, kPreloadTorque, c.preload_torque);
  expectPrior(after.calibration.te_offset, e, kTeOffset, c.te_offset);
  EXPECT_LT(c.mesh_stiffness_scale.reference_std, 0.0)
      << "the source file should not set reference_std (else this shows nothing)";

  // Everything else as before: gears, spring, dynamics, the bearings (from their files), the data
  // rules.
  EXPECT_EQ(after.gears.teeth, before.gears.teeth);
  EXPECT_EQ(after.gears.module, before.gears.module);
  EXPECT_EQ(after.gears.face_width, before.gears.face_width);
  EXPECT_EQ(after.anti_backlash.spring_stiffness, before.anti_backlash.spring_stiffness);
  EXPECT_EQ(after.mesh_samples, before.mesh_samples);
  EXPECT_EQ(after.dynamics.present, before.dynamics.present);
  EXPECT_EQ(after.dynamics.gear_inertia, before.dynamics.gear_inertia);
  EXPECT_EQ(after.dynamics.speed_rpm, before.dynamics.speed_rpm);
  for (std::size_t i = 0; i < after.bearings.size(); ++i) {
    EXPECT_EQ(after.bearings[i].name, before.bearings[i].name);
    EXPECT_EQ(after.bearings[i].shaft, before.bearings[i].shaft);
    EXPECT_EQ(after.bearings[i].spec.balls, before.bearings[i].spec.balls);
    EXPECT_EQ(after.bearings[i].spec.ball_diameter, before.bearings[i].spec.ball_diameter);
    EXPECT_EQ(after.bearings[i].axial_preload, before.bearings[i].axial_preload);
    EXPECT_EQ(after.bearings[i].radial_preload, before.bearings[i].radial_preload);
    EXPECT_EQ(after.bearings[i].mesh_load_share, before.bearings[i].mesh_load_share);
  }
  EXPECT_EQ(after.calibration.baseline_torque, before.calibration.baseline_torque);
  EXPECT_EQ(after.calibration.gate, before.calibration.gate);

  // The header says which bag, when, and what the data did not identify; the bearing file resolves
  // from the new directory by its absolute path.
  const std::string text = read(out);
  EXPECT_NE(text.find("/data/rig_run.bag"), std::string::npos) << text;
  EXPECT_NE(text.find("recorded 2026-01-01T00:00:00Z"), std::string::npos) << text;
  EXPECT_NE(text.find("Not identified (posterior std not below half the drawing's spread; the "
                      "value stays near its prior): "
                      "gear_bearing_scale\n"),
            std::string::npos)
      << text;
  const std::string bearing_file =
      fs::weakly_canonical(kSource + "/config/bearings/servo_7000ac.yaml").string();
  EXPECT_NE(text.find("file: " + bearing_file), std::string::npos) << text;
  EXPECT_EQ(text.find("../../config/bearings"), std::string::npos) << text;

  // And it calibrates again: the written file is a valid --config for the next run.
  const fs::path again = out.parent_path() / "again.yaml";
  writeCalibratedGearbox(out.string(), e, again.string(), provenance());
  const RigConfig twice = loadRigFile(again.string());
  EXPECT_EQ(twice.mesh_stiffness_scale, e.value[kMeshScale]);
  // A second calibration keeps the drawing's spread, not the first one's posterior std.
  EXPECT_EQ(twice.calibration.mesh_stiffness_scale.reference_std, c.mesh_stiffness_scale.std);
  EXPECT_EQ(twice.calibration.preload_torque.reference_std, c.preload_torque.reference());
  // The bearing scale not identified, as the first file (the same mean): the same converted spread.
  EXPECT_EQ(twice.calibration.gear_bearing_scale.reference_std,
            after.calibration.gear_bearing_scale.reference_std);
}

TEST(CalibratedGearbox, KeepsRelativeFilesInTheSameDirectory) {
  const fs::path dir = scratch("same_dir");
  fs::copy_file(kSource + "/config/bearings/servo_7000ac.yaml", dir / "servo_7000ac.yaml");
  std::string text = read(kConfig);
  for (std::size_t at;
       (at = text.find("../../config/bearings/servo_7000ac.yaml")) != std::string::npos;) {
    text.replace(at, std::string("../../config/bearings/servo_7000ac.yaml").size(),
                 "servo_7000ac.yaml");
  }
  std::ofstream(dir / "gearbox.yaml") << text;
  const CalibrationEstimate e = fitted();
  writeCalibratedGearbox((dir / "gearbox.yaml").string(), e, (dir / "calibrated.yaml").string(),
                         provenance());
  EXPECT_NE(read(dir / "calibrated.yaml").find("file: servo_7000ac.yaml"), std::string::npos);
  const RigConfig rig = loadRigFile((dir / "calibrated.yaml").string());
  EXPECT_EQ(rig.bearings[0].stiffness_scale, e.value[kPinionBearingScale]);
  EXPECT_EQ(rig.bearings[1].stiffness_scale, e.value[kGearBearingScale]);
}

TEST(CalibratedGearbox, AnOrdinaryGearGetsNoPreload) {
  // No scissor spring: the preload is held (prior std 0), and no anti_backlash block is invented.
  const fs::path dir = scratch("ordinary");
  std::string text = read(kSource + "/test/data/ordinary_servo.yaml");
  const std::string rel = "../../config/bearings/servo_7000ac.yaml";
  for (std::size_t at; (at = text.find(rel)) != std::string::npos;)
    text.replace(at, rel.size(), kSource + "/config/bearings/servo_7000ac.yaml");
  std::ofstream(dir / "ordinary.yaml") << text << "calibration: {}\n";
  CalibrationEstimate e = fitted();
  e.value[kPreloadTorque] = 0.0;
  e.std[kPreloadTorque] = e.prior_std[kPreloadTorque] = 0.0;
  e.identified[kPreloadTorque] = false;
  writeCalibratedGearbox((dir / "ordinary.yaml").string(), e, (dir / "calibrated.yaml").string(),
                         provenance());
  const std::string out = read(dir / "calibrated.yaml");
  EXPECT_EQ(out.find("anti_backlash"), std::string::npos) << out;
  EXPECT_NE(out.find("# Held (prior std 0, not estimated): preload_torque\n"), std::string::npos)
      << out;
  const RigConfig rig = loadRigFile((dir / "calibrated.yaml").string());
  EXPECT_EQ(rig.anti_backlash.spring_stiffness, 0.0);
  EXPECT_EQ(rig.mesh_stiffness_scale, e.value[kMeshScale]);
  EXPECT_EQ(rig.calibration.te_offset.mean, e.value[kTeOffset]);
}

TEST(CalibratedGearbox, RefusesWithoutACalibration) {
  const fs::path dir = scratch("refusals");
  const fs::path out = dir / "calibrated.yaml";
  try {
    writeCalibratedGearbox(kSource + "/test/data/perturbed_servo.yaml", fitted(), out.string(),
                           provenance());  // no calibration: block
    ADD_FAILURE() << "a gearbox without a calibration block: accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("has no calibration: block"), std::string::npos)
        << e.what();
  }
  CalibrationEstimate none = fitted();
  none.updates = 0;
  none.outcome = WindowOutcome::kNoBaseline;
  try {
    writeCalibratedGearbox(kConfig, none, out.string(), provenance());
    ADD_FAILURE() << "no window updated: accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "no window of the bag updated the calibration (12 windows: 3 baseline, 1 gated, "
                  "1 not excited; last: no baseline yet"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(out));
}

TEST(CalibratedGearbox, NumbersReadBackExactlyInYaml11) {
  EXPECT_EQ(yamlNumber(1.0), "1.0");
  EXPECT_EQ(yamlNumber(0.1), "0.1");
  EXPECT_EQ(yamlNumber(-2.5), "-2.5");
  EXPECT_EQ(yamlNumber(1e-7), "1.0e-07");
  EXPECT_EQ(yamlNumber(1e20), "1.0e+20");
  EXPECT_EQ(yamlNumber(1.5e-300), "1.5e-300");
  for (double v : {0.83123456789012345, 3.2109876543210987e-7, 1e-7, 12345678.9}) {
    EXPECT_EQ(YAML::Load(yamlNumber(v)).as<double>(), v) << yamlNumber(v);
  }
}

}  // namespace
}  // namespace drivetrain_stiffness

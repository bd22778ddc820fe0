// RigVisualizer's display scale follows the run-time settings' rule (requireExaggeration,
// runtime_settings.hpp): the same values refused with the same message, the same edges accepted,
// from the constructor and from setExaggeration (which keeps the last scale on a refusal).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/pipeline/runtime_settings.hpp"
#include "drivetrain_stiffness/ros/rig_visualization.hpp"

using namespace drivetrain_stiffness;

namespace {

std::string settingsRefusal(double exaggeration) {
  RuntimeSettings s;
  s.exaggeration = exaggeration;
  try {
    s.validate();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return {};
}

}  // namespace

TEST(RigVisualizer, ExaggerationFollowsTheSettingsRule) {
  const RigConfig rig = loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  const AntiBacklashMesh mesh(rig);
  const auto make = [&](double exaggeration) {
    return RigVisualizer(mesh.geometry(), rig.gears.face_width, 17.7, VisualizationFrames{}, exaggeration);
  };
  RigVisualizer v = make(2e4);
  for (const double value : {0.999, 1.0000001e8, -1.0, 0.0, std::nan(""), HUGE_VAL}) {
    const std::string expected = settingsRefusal(value);
    ASSERT_EQ(expected.rfind("exaggeration = ", 0), 0u) << value << " accepted by the settings";
    try {
      make(value);
      ADD_FAILURE() << "constructor accepted " << value;
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()), expected);
    }
    try {
      v.setExaggeration(value);
      ADD_FAILURE() << "setExaggeration accepted " << value;
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()), expected);
    }
    EXPECT_EQ(v.exaggeration(), 2e4);
  }
  for (const double value : {1.0, 1e8}) {
    EXPECT_EQ(settingsRefusal(value), "");
    EXPECT_EQ(make(value).exaggeration(), value);
    v.setExaggeration(value);
    EXPECT_EQ(v.exaggeration(), value);
  }
}

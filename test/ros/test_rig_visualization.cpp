// RigVisualizer's display scale follows the run-time settings' rule (requireExaggeration,
// runtime_settings.hpp): the same values refused with the same message, the same edges accepted,
// from the constructor and from setExaggeration (which keeps the last scale on a refusal). Its
// frames turn as the gears do; and the encoders' JointState is read by the configured joint names
// (toMotionInput, shared by the node and drivetrain_replay).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/pipeline/runtime_settings.hpp"
#include "drivetrain_stiffness/ros/message_conversion.hpp"
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
  const RigConfig rig =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  const AntiBacklashMesh mesh(rig);
  const auto make = [&](double exaggeration) {
    return RigVisualizer(mesh.geometry(), rig.gears.face_width, 17.7, VisualizationFrames{},
                         exaggeration);
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

namespace {
/// The angle of a rotation about z from its quaternion (the frames turn about z only).
double yaw(const geometry_msgs::Quaternion& q) { return 2.0 * std::atan2(q.z, q.w); }
}  // namespace

TEST(RigVisualizer, FramesTurnAsTheGearsDo) {
  // The pinion frame at the angle given (the encoders', RigPipeline::encoderPinionAngle); the gear
  // the other way at z_p / z_g (seed 000 Table 1: 20 / 40), lagging by the torsional deflection
  // x = r_b1 theta_p - r_b2 theta_g (seed 000 eq 12) scaled for display: exaggeration x / r_b2.
  const RigConfig rig =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  const AntiBacklashMesh mesh(rig);
  const double exaggeration = 2e4;
  const RigVisualizer v(mesh.geometry(), rig.gears.face_width, 17.7, VisualizationFrames{},
                        exaggeration);
  DynamicsSample s;
  s.state.setZero();
  for (const double angle : {0.0, 0.7, -2.5, 3.0}) {
    const auto tf = v.transforms(ros::Time(1.0), s, angle);
    ASSERT_EQ(tf.size(), 2u);
    EXPECT_NEAR(std::remainder(yaw(tf[0].transform.rotation) - angle, 2.0 * M_PI), 0.0, 1e-12)
        << angle;
    EXPECT_NEAR(std::remainder(yaw(tf[1].transform.rotation) + 20.0 / 40.0 * angle, 2.0 * M_PI),
                0.0, 1e-12)
        << angle;
  }
  s.state[2] = 1e-6;  // [m] the pinion 1 um ahead along the line of action
  const auto tf = v.transforms(ros::Time(1.0), s, 0.0);
  EXPECT_NEAR(yaw(tf[1].transform.rotation), exaggeration * 1e-6 / mesh.geometry().baseRadius(1),
              1e-12);
  EXPECT_EQ(yaw(tf[0].transform.rotation), 0.0)
      << "the deflection turns the gear's frame, not the pinion's";
}

TEST(MessageConversion, JointStatesAreReadByTheConfiguredNames) {
  // The pinion's position and velocity and the gear's position by name, in any order; velocity
  // may be absent (then differentiated: the encoders rule), the gear may be absent (no ratio
  // check); without the pinion's position the message is refused, saying why (counted by the
  // pipeline).
  const JointNames names{"motor", "output"};
  sensor_msgs::JointState m;
  m.name = {"output", "spindle", "motor"};
  m.position = {-0.25, 9.0, 0.5};
  m.velocity = {-1.0, 9.0, 2.0};
  std::string why;
  std::optional<MotionInput> in = toMotionInput(m, names, why);
  ASSERT_TRUE(in.has_value()) << why;
  EXPECT_EQ(in->pinion_angle, 0.5);
  ASSERT_TRUE(in->pinion_velocity.has_value());
  EXPECT_EQ(*in->pinion_velocity, 2.0);
  ASSERT_TRUE(in->gear_angle.has_value());
  EXPECT_EQ(*in->gear_angle, -0.25);
  m.velocity.clear();  // not measured
  in = toMotionInput(m, names, why);
  ASSERT_TRUE(in.has_value());
  EXPECT_FALSE(in->pinion_velocity.has_value());
  m.name = {"motor"};
  m.position = {0.5};
  in = toMotionInput(m, names, why);
  ASSERT_TRUE(in.has_value());
  EXPECT_FALSE(in->gear_angle.has_value());
  // The default names do not match this rig's joints: refused, naming the parameter and the
  // joints the message has (printable whatever their bytes).
  EXPECT_FALSE(toMotionInput(m, JointNames{}, why).has_value());
  EXPECT_EQ(why, "no joint named 'pinion' (~pinion_joint); the message has joints 'motor'");
  EXPECT_EQ(jointNamesOf(m), "joints 'motor'");
  sensor_msgs::JointState odd;
  odd.name = {"a\xff", "b", "c", "d", "e", "f"};
  EXPECT_EQ(jointNamesOf(odd), "joints 'a\\xff', 'b', 'c', 'd', ... (6 in all)");
  EXPECT_EQ(jointNamesOf(sensor_msgs::JointState{}), "no joint names");
  m.position.clear();  // a name without a position
  EXPECT_FALSE(toMotionInput(m, names, why).has_value());
  EXPECT_EQ(why, "joint 'motor' has no position (0 positions for 1 names)");
}

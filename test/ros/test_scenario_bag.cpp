// drivetrain_rig_sim's bag (src/tools/rig_sim/scenario_bag.hpp) read back by rosbag::View: the
// encoders' joint_states are sensor_msgs/JointState with the type's md5sum and definition
// (ros::message_traits), names [pinion, gear], positions equal to the scenario's readings and
// within half a count of the run-up's closed form theta = s1 t^2 / (2 T), velocities or none, no
// effort, an empty frame_id, header.seq from 0 and stamps = record times = epoch + t; the torque
// and preload beside them.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include <geometry_msgs/WrenchStamped.h>
#include <ros/message_traits.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/JointState.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "scenarios/rig_scenarios.hpp"
#include "rig_sim/scenario_bag.hpp"

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() {  // z_p = 20, z_g = 40 (seed 000 Table 1)
  static const RigConfig r =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  return r;
}

constexpr double kCount = kTwoPi / 1048576.0;  // one count of a 2^20-count encoder [rad]

std::string tempBag(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("scenario_bag_test_" + std::to_string(::getpid()) + "_" + name + ".bag"))
      .string();
}

std::vector<RigEvent> scenario(const std::string& name, double duration, bool velocity = true) {
  ScenarioSpec spec;
  spec.name = name;
  spec.duration = duration;
  spec.joint_velocity = velocity;
  return makeScenario(rig(), spec);
}

std::vector<RigEvent> readings(const std::vector<RigEvent>& events) {
  std::vector<RigEvent> out;
  for (const RigEvent& e : events) {
    if (e.motion) out.push_back(e);
  }
  return out;
}

}  // namespace

TEST(ScenarioBag, JointStatesAreReadableByRosbagWithTheRightNamesAndPositions) {
  const double T = 0.2, s1 = 6000.0 * kTwoPi / 60.0;  // run-up 0 -> 6000 rpm over 0.2 s
  const std::vector<RigEvent> events = scenario("run_up", T);
  const std::string path = tempBag("run_up");
  const ScenarioBagCounts n = writeScenarioBag(events, ScenarioBagOptions{}, path);
  EXPECT_EQ(n.joint_states, 200u);
  EXPECT_EQ(n.torque, 200u);
  EXPECT_EQ(n.preload, 1u);
  const std::vector<RigEvent> expected = readings(events);

  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery("/joint_states"));
  ASSERT_EQ(view.size(), 200u);
  std::size_t k = 0;
  for (const rosbag::MessageInstance& m : view) {
    EXPECT_EQ(m.getDataType(), "sensor_msgs/JointState");
    EXPECT_EQ(m.getMD5Sum(),
              std::string(ros::message_traits::MD5Sum<sensor_msgs::JointState>::value()));
    EXPECT_EQ(m.getMessageDefinition(),
              std::string(ros::message_traits::Definition<sensor_msgs::JointState>::value()));
    const sensor_msgs::JointState::ConstPtr j = m.instantiate<sensor_msgs::JointState>();
    ASSERT_TRUE(j);
    const double t = k * 1e-3;
    EXPECT_EQ(j->header.seq, k);
    EXPECT_EQ(j->header.stamp, ros::Time(1767225600, static_cast<std::uint32_t>(k * 1000000)));
    EXPECT_EQ(m.getTime(), j->header.stamp);
    EXPECT_EQ(j->header.frame_id, "");
    ASSERT_EQ(j->name, (std::vector<std::string>{"pinion", "gear"}));
    ASSERT_EQ(j->position.size(), 2u);
    ASSERT_EQ(j->velocity.size(), 2u);
    EXPECT_TRUE(j->effort.empty());
    EXPECT_EQ(j->position[0], expected[k].motion->pinion_angle);
    EXPECT_EQ(j->position[1], *expected[k].motion->gear_angle);
    EXPECT_EQ(j->velocity[0], *expected[k].motion->pinion_velocity);
    EXPECT_EQ(j->velocity[1], *expected[k].gear_velocity);
    // Independently of the scenario code: the run-up's kinematics, the encoder grid, the ratio.
    EXPECT_LE(std::abs(j->position[0] - s1 * t * t / (2.0 * T)), 0.5 * kCount + 1e-12) << t;
    EXPECT_LE(std::abs(j->position[1] + 0.5 * s1 * t * t / (2.0 * T)), 0.5 * kCount + 1e-12) << t;
    EXPECT_NEAR(j->velocity[0], s1 * t / T, 1e-9) << t;
    EXPECT_NEAR(j->velocity[1], -0.5 * s1 * t / T, 1e-9) << t;
    for (double p : j->position) EXPECT_NEAR(p / kCount, std::round(p / kCount), 1e-6) << t;
    ++k;
  }
  // The torque beside them on /torque, one message per reading.
  rosbag::View torque(bag, rosbag::TopicQuery("/torque"));
  EXPECT_EQ(torque.size(), 200u);
  EXPECT_EQ(torque.begin()->instantiate<geometry_msgs::WrenchStamped>()->wrench.torque.z, 0.1);
  bag.close();
  std::filesystem::remove(path);
}

TEST(ScenarioBag, NoVelocityOtherTopicAndJointNames) {
  const std::string path = tempBag("reverse");
  ScenarioBagOptions o;
  o.joint_topic = "/rig/joint_states";
  o.pinion_joint = "motor";
  o.gear_joint = "output";
  writeScenarioBag(scenario("reverse", 0.1, false), o, path);
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  EXPECT_EQ(rosbag::View(bag, rosbag::TopicQuery("/joint_states")).size(), 0u);
  rosbag::View view(bag, rosbag::TopicQuery("/rig/joint_states"));
  ASSERT_EQ(view.size(), 100u);
  for (const rosbag::MessageInstance& m : view) {
    const sensor_msgs::JointState::ConstPtr j = m.instantiate<sensor_msgs::JointState>();
    ASSERT_TRUE(j);
    EXPECT_EQ(j->name, (std::vector<std::string>{"motor", "output"}));
    EXPECT_EQ(j->position.size(), 2u);
    EXPECT_TRUE(j->velocity.empty());
    EXPECT_TRUE(j->effort.empty());
  }
  bag.close();
  std::filesystem::remove(path);
}

TEST(ScenarioBag, JointRateZeroWritesNoJointStatesConnection) {
  const std::string path = tempBag("ripple");
  ScenarioSpec spec;
  spec.name = "torque_ripple";
  spec.duration = 0.1;
  spec.joint_rate = 0.0;
  const ScenarioBagCounts n =
      writeScenarioBag(makeScenario(rig(), spec), ScenarioBagOptions{}, path);
  EXPECT_EQ(n.joint_states, 0u);
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View all(bag);
  EXPECT_EQ(all.getConnections().size(), 2u);  // /torque and /preload only
  EXPECT_EQ(all.size(), 101u);
  bag.close();
  std::filesystem::remove(path);
}

TEST(ScenarioBag, FaultsStampTheReadingsWithTheLoopedRecording) {
  // From 3/4 of the duration on, every stamp runs 0.6 duration behind its record time.
  const std::string path = tempBag("faults");
  writeScenarioBag(scenario("faults", 2.0), ScenarioBagOptions{}, path);
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::size_t behind = 0, k = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/joint_states"))) {
    const sensor_msgs::JointState::ConstPtr j = m.instantiate<sensor_msgs::JointState>();
    EXPECT_EQ(j->header.seq, k++);
    const double lag = (m.getTime() - j->header.stamp).toSec();
    if (lag != 0.0) {
      EXPECT_NEAR(lag, 1.2, 1e-9);
      ++behind;
    }
  }
  EXPECT_EQ(k, 2000u);
  EXPECT_EQ(behind, 500u);  // t = 1.5 .. 1.999 s
  bag.close();
  std::filesystem::remove(path);
}

TEST(ScenarioBag, RefusesEmptyNamesNamingTheOption) {
  const std::vector<RigEvent> events = scenario("run_up", 0.01);
  ScenarioBagOptions o;
  o.gear_joint = "";
  try {
    writeScenarioBag(events, o, tempBag("refused"));
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), "gear_joint = '': must not be empty");
  }
  EXPECT_FALSE(std::filesystem::exists(tempBag("refused")));  // refused before the bag is opened
}

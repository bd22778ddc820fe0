// replay.launch end to end: rosbag play --clock -l feeds the bundled torque-ripple bag (2 s, stamps
// from 2026-01-01T00:00:00, drivetrain_rig_sim) into the node on sim time. The outputs carry the
// bag's stamps (not wall time), and when the loop restarts the ROS clock jumps back: the node must
// reset (clock_jump_resets, or stamp_jump_resets when the loop's first messages beat the clock
// jump, on /diagnostics) and then answer the replayed inputs again.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>

#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"

namespace {

constexpr double kBagStart = 1767225600.0;  // drivetrain_rig_sim's default epoch [s]
constexpr double kBagLength = 2.0;          // [s]

struct Outputs {
  std::vector<drivetrain_stiffness::TransmissionError> te;
  std::vector<drivetrain_stiffness::Stiffness> stiffness;
  std::map<std::string, std::string> diagnostics;
};

bool waitWall(const std::function<bool()>& done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return done();
}

/// How often the stamps go back from one message to the next.
int stepsBack(const std::vector<drivetrain_stiffness::TransmissionError>& te) {
  int backwards = 0;
  for (std::size_t i = 1; i < te.size(); ++i)
    backwards += te[i].header.stamp < te[i - 1].header.stamp ? 1 : 0;
  return backwards;
}

/// Every output carries a bag stamp and finite values; the TE's torque is the bag's.
void expectBagStamps(const std::vector<drivetrain_stiffness::Stiffness>& stiffness,
                     const std::vector<drivetrain_stiffness::TransmissionError>& te) {
  for (const auto& m : stiffness) {
    const double t = m.header.stamp.toSec();
    EXPECT_GE(t, kBagStart - 1e-6);
    EXPECT_LE(t, kBagStart + kBagLength + 1e-6);
    for (const auto& b : m.bearings) EXPECT_TRUE(std::isfinite(b.radial_stiffness));
  }
  // Transmission error: bag stamps on the 1 ms grid, finite; going back exactly once per loop.
  for (std::size_t i = 0; i < te.size(); ++i) {
    const double t = te[i].header.stamp.toSec();
    EXPECT_GE(t, kBagStart - 1e-6);
    EXPECT_LE(t, kBagStart + kBagLength + 1e-6);
    EXPECT_TRUE(std::isfinite(te[i].dynamic_te));
    EXPECT_NEAR(te[i].torque, 0.1, 0.1 * 0.07 + 1e-12);  // the bag's 0.1 N*m with 5 % + 2 % ripple
  }
}

}  // namespace

TEST(ReplayLaunch, OutputsCarryBagStampsAndTheLoopResets) {
  ros::NodeHandle nh;
  Outputs out;
  std::mutex mutex;
  auto te_sub = nh.subscribe<drivetrain_stiffness::TransmissionError>(
      "transmission_error", 100000,
      [&](const drivetrain_stiffness::TransmissionError::ConstPtr& m) {
        std::lock_guard<std::mutex> l(mutex);
        out.te.push_back(*m);
      });
  auto st_sub = nh.subscribe<drivetrain_stiffness::Stiffness>(
      "stiffness", 100000, [&](const drivetrain_stiffness::Stiffness::ConstPtr& m) {
        std::lock_guard<std::mutex> l(mutex);
        out.stiffness.push_back(*m);
      });
  auto diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
        std::lock_guard<std::mutex> l(mutex);
        for (const auto& s : a->status)
          if (s.name.find("stiffness_estimator") != std::string::npos)
            for (const auto& kv : s.values) out.diagnostics[kv.key] = kv.value;
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();
  auto counter = [&](const std::string& key) {
    std::lock_guard<std::mutex> l(mutex);
    auto it = out.diagnostics.find(key);
    return it == out.diagnostics.end() ? -1L : std::stol(it->second);
  };
  // The first pass (1 s at rate 2 plus the start delay) and the loop's restart: the clock jump
  // resets (the clock-jump rule), or, when the loop's first messages beat the /clock jump, the
  // stamps do (source restarted).
  ASSERT_TRUE(waitWall(
      [&] { return counter("clock_jump_resets") + counter("stamp_jump_resets") >= 1; }, 60.0))
      << "no reset when the bag looped";
  const std::size_t te_at_reset = [&] {
    std::lock_guard<std::mutex> l(mutex);
    return out.te.size();
  }();
  ASSERT_TRUE(waitWall(
      [&] {
        std::lock_guard<std::mutex> l(mutex);
        return out.te.size() > te_at_reset + 200;
      },
      30.0))
      << "no transmission error after the reset";
  // A snapshot of what arrived, then the diagnostics are given time to catch up with it: a loop's
  // first samples can reach us before the next /diagnostics report counts that loop's reset (the
  // report comes once a second), so reading the counter at the same moment could see one reset
  // fewer than the samples show.
  std::vector<drivetrain_stiffness::Stiffness> stiffness;
  std::vector<drivetrain_stiffness::TransmissionError> te;
  {
    std::lock_guard<std::mutex> l(mutex);
    stiffness = out.stiffness;
    te = out.te;
  }
  const int backwards = stepsBack(te);
  waitWall([&] { return counter("clock_jump_resets") + counter("stamp_jump_resets") >= backwards; },
           10.0);
  spinner.stop();
  const long resets = counter("clock_jump_resets") + counter("stamp_jump_resets");
  const long invalid = counter("rejected_invalid_value");

  std::lock_guard<std::mutex> l(mutex);
  ASSERT_GT(stiffness.size(), 500u);
  expectBagStamps(stiffness, te);
  EXPECT_GE(backwards, 1);
  EXPECT_LE(backwards, resets);
  EXPECT_EQ(invalid, 0);
  std::cout << "replay.launch: " << stiffness.size() << " stiffness, " << te.size()
            << " transmission_error; "
            << "clock_jump_resets " << out.diagnostics["clock_jump_resets"] << ", out of order "
            << out.diagnostics["rejected_out_of_order"] << std::endl;
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "replay_launch_rostest");
  return RUN_ALL_TESTS();
}

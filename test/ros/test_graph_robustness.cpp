// The estimator as a nodelet in a running graph (rig.launch nodelet:=true): it answers torque with
// the input's stamp; zero stamps, late stamps and bursts follow the documented rules and show on
// /diagnostics; dynamic_reconfigure switches the fidelity and damping at run time; and at start-up
// every invalid parameter stops the class with an error naming it (checked in-process).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <mutex>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>

#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/ros/stiffness_estimator_ros.hpp"

using drivetrain_stiffness::InvalidInput;

namespace {

const std::uint32_t kT0 = 1767225600;  // a wall-clock epoch for the stamps [s]

bool waitWall(const std::function<bool()>& done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

class GraphTest : public testing::Test {
 protected:
  void SetUp() override {
    // As rosbag play publishes a recording (has_header false): roscpp then sends header.seq as we
    // set it instead of numbering the messages itself, so the test can make a gap.
    ros::AdvertiseOptions options = ros::AdvertiseOptions::create<geometry_msgs::WrenchStamped>(
        "torque", 100, ros::SubscriberStatusCallback(), ros::SubscriberStatusCallback(),
        ros::VoidConstPtr(), nullptr);
    options.has_header = false;
    torque_pub_ = nh_.advertise(options);
    stiffness_sub_ = nh_.subscribe<drivetrain_stiffness::Stiffness>(
        "stiffness", 1000, [this](const drivetrain_stiffness::Stiffness::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          stiffness_.push_back(*m);
        });
    te_sub_ = nh_.subscribe<drivetrain_stiffness::TransmissionError>(
        "transmission_error", 100000,
        [this](const drivetrain_stiffness::TransmissionError::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          te_.push_back(*m);
        });
    diag_sub_ = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
          std::lock_guard<std::mutex> l(m_);
          for (const auto& s : a->status)
            if (s.name.find("stiffness_estimator") != std::string::npos)
              for (const auto& kv : s.values) diagnostics_[kv.key] = kv.value;
        });
    spinner_.start();
    ASSERT_TRUE(waitWall(
        [this] {
          return torque_pub_.getNumSubscribers() > 0 && stiffness_sub_.getNumPublishers() > 0 &&
                 te_sub_.getNumPublishers() > 0;
        },
        30.0))
        << "the nodelet did not come up";
    // getNumPublishers() counts a publisher once the master reports it, before the TCP link is up:
    // messages sent in between are lost. Let the links settle (as the load generator does).
    ros::WallDuration(0.5).sleep();
  }
  // Stamp = the epoch plus `offset` seconds, exact to the nanosecond (ros::Time(1.7e9 + 0.05) would
  // round 0.05 to 0.049999952 s: one grid sample short). offset < -1e9 gives the zero stamp.
  void send(double offset, double torque, const std::string& frame = "pinion",
            std::uint32_t skip = 0) {
    geometry_msgs::WrenchStamped w;
    w.header.stamp = offset < -1e9 ? ros::Time(0, 0) : ros::Time(kT0, 0) + ros::Duration(offset);
    w.header.frame_id = frame;  // ~torque_frame (pinion)
    seq_ += skip;               // messages "lost on the way"
    w.header.seq = seq_++;
    w.wrench.torque.z = torque;
    torque_pub_.publish(w);
  }
  std::uint32_t seq_ = 0;
  std::size_t answers() {
    std::lock_guard<std::mutex> l(m_);
    return stiffness_.size();
  }
  std::string diagnostic(const std::string& key) {
    std::lock_guard<std::mutex> l(m_);
    auto it = diagnostics_.find(key);
    return it == diagnostics_.end() ? "" : it->second;
  }
  bool diagnosticIs(const std::string& key, const std::string& value) {
    return waitWall([&] { return diagnostic(key) == value; }, 5.0);
  }

  ros::NodeHandle nh_;
  ros::AsyncSpinner spinner_{2};
  ros::Publisher torque_pub_;
  ros::Subscriber stiffness_sub_, te_sub_, diag_sub_;
  std::mutex m_;
  std::vector<drivetrain_stiffness::Stiffness> stiffness_;
  std::vector<drivetrain_stiffness::TransmissionError> te_;
  std::map<std::string, std::string> diagnostics_;
};

}  // namespace

TEST_F(GraphTest, NodeletAnswersAndAppliesTheStampRules) {
  send(0.0, 0.1);
  ASSERT_TRUE(waitWall([this] { return answers() >= 1; }, 5.0));
  {
    std::lock_guard<std::mutex> l(m_);
    EXPECT_EQ(stiffness_.back().header.stamp, ros::Time(kT0, 0));  // stamped with the input's time
  }
  // The zero-stamp rule: a zero stamp is rejected; out of order: 0.5 s late (within
  // ~stamp_jump_back) is rejected.
  send(-2e9, 0.1);  // zero stamp
  send(0.1, 0.1);   // accepted (answer 2)
  send(-0.4, 0.1);  // 0.5 s before the last one: out of order
  // The burst rule: a burst of five equal stamps is accepted (answers 3-7) and releases no extra
  // samples.
  for (int i = 0; i < 5; ++i) send(0.2, 0.1 + 0.01 * i);
  send(0.203, 0.1);  // answer 8: three samples with the last torque of the burst held
  // Transport rules on the graph: a torque in the gear's frame is refused, and a gap of 4 in the
  // publisher's numbering is counted as dropped (the caller id comes from the connection).
  send(0.2031, -0.1, "gear");
  send(0.2032, 0.14, "pinion", 4);  // answer 9; its own stamp releases no new grid sample
  ASSERT_TRUE(waitWall([this] { return answers() >= 9; }, 5.0)) << answers();
  EXPECT_TRUE(diagnosticIs("rejected_zero_stamp", "1"));
  EXPECT_TRUE(diagnosticIs("rejected_out_of_order", "1"));
  EXPECT_TRUE(diagnosticIs("rejected_wrong_frame", "1"));
  EXPECT_TRUE(diagnosticIs("dropped_torque", "4"));
  EXPECT_TRUE(diagnosticIs("accepted_torque", "9"));
  ASSERT_TRUE(waitWall(
      [this] {
        std::lock_guard<std::mutex> l(m_);
        return te_.size() >= 203;
      },
      5.0));
  std::lock_guard<std::mutex> l(m_);
  EXPECT_EQ(te_.size(), 203u);  // (kT0, kT0 + 0.203] on the 1 ms grid
  EXPECT_DOUBLE_EQ(te_.back().torque, 0.14);
}

TEST_F(GraphTest, DynamicReconfigureSwitchesFidelityAndDamping) {
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::StrParameter fidelity;
  fidelity.name = "fidelity";
  fidelity.value = "quasi_static";
  dynamic_reconfigure::DoubleParameter damping;
  damping.name = "mesh_damping_ratio";
  damping.value = 0.1;
  srv.request.config.strs.push_back(fidelity);
  srv.request.config.doubles.push_back(damping);
  ASSERT_TRUE(ros::service::waitForService("/stiffness_estimator/set_parameters", 10000));
  ASSERT_TRUE(ros::service::call("/stiffness_estimator/set_parameters", srv));
  EXPECT_TRUE(diagnosticIs("dynamics_fidelity", "quasi_static"));
  // Quasi-static: the torsional mode in equilibrium, so the deflection equals F / k_s exactly.
  const double t = kT0 + 100.0;  // well after the other test's inputs: a gap restart, then samples
  send(100.0, 0.1);
  send(100.05, 0.1);
  ASSERT_TRUE(waitWall(
      [this, t] {
        std::lock_guard<std::mutex> l(m_);
        return !te_.empty() && te_.back().header.stamp.toSec() >= t + 0.05 - 1e-6;
      },
      5.0))
      << "last event: " << diagnostic("last_event") << "; dynamics errors "
      << diagnostic("dynamics_errors") << "; accepted " << diagnostic("accepted_torque") << "; te "
      << diagnostic("transmission_error_published") << "; received " << te_.size();
  std::lock_guard<std::mutex> l(m_);
  int checked = 0;
  for (const auto& m : te_) {
    if (m.header.stamp.toSec() < t) continue;
    EXPECT_NEAR(m.dynamic_te, m.static_te, 1e-12 * std::abs(m.static_te));
    ++checked;
  }
  EXPECT_EQ(checked, 50);
}

// Start-up validation, in-process: each bad parameter makes the constructor throw InvalidInput
// naming the parameter (the node prints it and exits 1; the nodelet manager reports a failed load).
TEST(StartupValidation, EveryBadParameterIsNamed) {
  std::string gearbox;
  ASSERT_TRUE(ros::NodeHandle("~").getParam("gearbox_config", gearbox));
  struct Case {
    const char* name;
    XmlRpc::XmlRpcValue value;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"output_rate", XmlRpc::XmlRpcValue(-1.0), "~output_rate"},
      {"output_rate", XmlRpc::XmlRpcValue("fast"), "~output_rate: has the wrong type"},
      {"max_preload", XmlRpc::XmlRpcValue("1.0e5"),
       "~max_preload: has the wrong type"},  // YAML 1.1 reads 1.0e5 as text
      {"spectrum_hop", XmlRpc::XmlRpcValue(0), "~spectrum_hop"},
      {"spectrum_window", XmlRpc::XmlRpcValue(4.2),
       "~spectrum_window"},  // roscpp rounds to 4: out of range
      {"fidelity", XmlRpc::XmlRpcValue("exact"), "fidelity"},
      {"exaggeration", XmlRpc::XmlRpcValue(0.5), "~exaggeration"},
      {"tf_rate", XmlRpc::XmlRpcValue(-1.0), "~tf_rate"},
      {"rig_frame", XmlRpc::XmlRpcValue("/rig"), "_frame"},
      {"deadline", XmlRpc::XmlRpcValue(0.0), "~deadline"},
      {"torque_queue_size", XmlRpc::XmlRpcValue(0), "~torque_queue_size"},
      {"bearing_load_tolerance", XmlRpc::XmlRpcValue(0.5), "bearing_load_tolerance"},
      {"resonance_threshold", XmlRpc::XmlRpcValue(2.0), "~resonance_threshold"},
      {"diagnostic_period", XmlRpc::XmlRpcValue(-1.0), "~diagnostic_period"},
      {"max_abs_torque", XmlRpc::XmlRpcValue(0.0), "~max_abs_torque"},
      {"max_gap", XmlRpc::XmlRpcValue(0.0), "~max_gap"},
      {"max_gap", XmlRpc::XmlRpcValue(1e5), "max_gap * output_rate"},
      {"stamp_jump_back", XmlRpc::XmlRpcValue(-1.0), "~stamp_jump_back"},
      {"clock_jump_back", XmlRpc::XmlRpcValue(-1.0), "~clock_jump_back"},
      {"pinion_speed_rpm", XmlRpc::XmlRpcValue(0.0), "pinion_speed_rpm"},
      {"stiffness_rate", XmlRpc::XmlRpcValue(-1.0), "~stiffness_rate"},
      {"dynamics", XmlRpc::XmlRpcValue("yes"), "~dynamics: has the wrong type"},
      {"calibrate", XmlRpc::XmlRpcValue("yes"), "~calibrate: has the wrong type"},
      {"max_interference", XmlRpc::XmlRpcValue(-1e-3), "~max_interference"},
      {"gearbox_config", XmlRpc::XmlRpcValue("/no/such/gearbox.yaml"), "/no/such/gearbox.yaml"},
  };
  int index = 0;
  for (const Case& c : cases) {
    const std::string ns = "/bad_parameters_" + std::to_string(index++);
    ros::NodeHandle pnh(ns);
    pnh.setParam("gearbox_config", gearbox);
    XmlRpc::XmlRpcValue value = c.value;
    pnh.setParam(c.name, value);
    try {
      drivetrain_stiffness::StiffnessEstimatorRos estimator(ros::NodeHandle(ns + "_public"), pnh);
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos)
          << c.name << ": " << e.what();
    }
  }
  // And the required parameter missing altogether.
  try {
    drivetrain_stiffness::StiffnessEstimatorRos estimator(ros::NodeHandle("/empty_public"),
                                                          ros::NodeHandle("/empty"));
    ADD_FAILURE() << "no gearbox_config: accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("~gearbox_config"), std::string::npos) << e.what();
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "graph_robustness_rostest");
  return RUN_ALL_TESTS();
}

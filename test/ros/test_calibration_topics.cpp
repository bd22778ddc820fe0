// The node's live calibration (docs/ros_api.md, the calibration rule) on the graph: with a gearbox
// that has a calibration block (test/data/calibration_servo.yaml), torque steps at 1000 rpm and the
// encoders' joint_states at 5 kHz (the first step at the baseline torque), the node publishes
// `measured_te` and `calibration`, and with them the encoder-driven dynamics' `transmission_error`
// and `mesh_period_stats`; every message equals, bit for bit (header.seq aside, which roscpp
// numbers itself), what the same RigPipeline and message conversion give in-process for the same
// inputs in the same order (what drivetrain_replay runs): the node against the replay with joint
// states. /diagnostics carries the calibration's outcome, counts and identified parameters, and
// calibration_published / measured_te_published match.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/ros/message_conversion.hpp"
#include "drivetrain_stiffness/ros/node_parameters.hpp"
#include "drivetrain_stiffness/ros/parameters.hpp"

namespace drivetrain_stiffness {
namespace {

const std::uint32_t kT0 = 1767225600;  // the stamps' epoch [s]
constexpr double kRate =
    5000.0;  // [Hz] joint_states: the second mesh harmonic (667 Hz) needs more than 1 kHz
constexpr double kSpeed = 1000.0 * kTwoPi / 60.0;  // [rad/s] pinion, the middle of the run-up
constexpr double kSegment = 0.37;  // [s] per torque step: three gear turns (0.12 s each)

bool waitWall(const std::function<bool()>& done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

/// What the node publishes, made in-process by the same conversion (MessageSink's calls).
struct CollectingSink : PipelineSink {
  std::string rig_frame, pinion_frame;
  std::vector<drivetrain_stiffness::Calibration> calibrations;
  std::vector<drivetrain_stiffness::MeasuredTe> measured_tes;
  std::vector<drivetrain_stiffness::TransmissionError> tes;
  std::vector<drivetrain_stiffness::MeshPeriodStats> periods;
  void transmissionError(Stamp stamp, const DynamicsSample& s, const SampleContext&) override {
    tes.push_back(toTransmissionErrorMsg(stamp, pinion_frame, s));
  }
  void meshPeriod(Stamp stamp, const MeshPeriodStatistics& s) override {
    periods.push_back(toMeshPeriodStatsMsg(stamp, pinion_frame, s));
  }
  void measuredTe(Stamp stamp, const MeasuredTeSample& s) override {
    measured_tes.push_back(toMeasuredTeMsg(stamp, pinion_frame, s));
  }
  void calibration(Stamp stamp, const CalibrationEstimate& e) override {
    calibrations.push_back(toCalibrationMsg(stamp, rig_frame, e));
  }
};

struct Input {
  bool torque = false;
  geometry_msgs::WrenchStamped wrench;
  sensor_msgs::JointState joints;
};

/// Torque steps: the baseline (at most calibration.baseline_torque), then two loads; the encoders
/// run up from 700 to 1300 rpm through the three steps (a speed that changes at every reading, as a
/// rig's run-up: the dynamics follow it on the sliced propagation), the gear at the tooth ratio (no
/// TE: the loaded windows are gated, which is as good a test of the plumbing as an update).
std::vector<std::vector<Input>> makeSegments(const RigConfig& rig, const JointNames& joints) {
  const double ratio = static_cast<double>(rig.gears.teeth[0]) / rig.gears.teeth[1];
  const double steps[] = {0.05, 0.1, 0.2};
  std::vector<std::vector<Input>> segments;
  std::int64_t k = 0;
  for (std::size_t s = 0; s < 3; ++s) {
    std::vector<Input> inputs;
    Input t;
    t.torque = true;
    t.wrench.header.stamp = ros::Time(kT0, 0) + ros::Duration(static_cast<double>(k) / kRate);
    t.wrench.header.frame_id = "pinion";
    t.wrench.wrench.torque.z = steps[s];
    inputs.push_back(t);
    for (; static_cast<double>(k) < kSegment * kRate * static_cast<double>(s + 1); ++k) {
      Input j;
      const double time = static_cast<double>(k) / kRate;
      j.joints.header.stamp = ros::Time(kT0, 0) + ros::Duration(time);
      j.joints.name = {joints.pinion, joints.gear};
      // omega = kSpeed (0.7 + 0.6 t / T), T the three segments; the angle its integral.
      const double span = 3.0 * kSegment;
      const double angle = kSpeed * (0.7 * time + 0.3 * time * time / span),
                   speed = kSpeed * (0.7 + 0.6 * time / span);
      j.joints.position = {angle, -ratio * angle};
      j.joints.velocity = {speed, -ratio * speed};
      inputs.push_back(j);
    }
    segments.push_back(inputs);
  }
  return segments;
}

/// The segments through `pipeline` in process, in the order the node takes them.
void feedInProcess(RigPipeline& pipeline, const std::vector<std::vector<Input>>& segments,
                   const JointNames& joints, PipelineSink& sink) {
  std::string why;
  for (const auto& segment : segments) {
    for (const Input& in : segment) {
      if (in.torque) {
        pipeline.torque(fromRosTime(in.wrench.header.stamp), in.wrench.wrench.torque.z, sink,
                        {"", 0, in.wrench.header.frame_id});
      } else {
        pipeline.motion(fromRosTime(in.joints.header.stamp), *toMotionInput(in.joints, joints, why),
                        sink);
      }
    }
  }
}

class CalibrationTopicsTest : public testing::Test {
 protected:
  void SetUp() override {
    torque_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>("torque", 100);
    joints_pub_ = nh_.advertise<sensor_msgs::JointState>("joint_states", 1000);
    calibration_sub_ = nh_.subscribe<drivetrain_stiffness::Calibration>(
        "calibration", 1000, [this](const drivetrain_stiffness::Calibration::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          calibration_.push_back(*m);
        });
    measured_te_sub_ = nh_.subscribe<drivetrain_stiffness::MeasuredTe>(
        "measured_te", 100000, [this](const drivetrain_stiffness::MeasuredTe::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          measured_te_.push_back(*m);
        });
    te_sub_ = nh_.subscribe<drivetrain_stiffness::TransmissionError>(
        "transmission_error", 100000,
        [this](const drivetrain_stiffness::TransmissionError::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          te_.push_back(*m);
        });
    period_sub_ = nh_.subscribe<drivetrain_stiffness::MeshPeriodStats>(
        "mesh_period_stats", 100000,
        [this](const drivetrain_stiffness::MeshPeriodStats::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          periods_.push_back(*m);
        });
    diag_sub_ = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
          std::lock_guard<std::mutex> l(m_);
          for (const auto& s : a->status)
            if (s.name.find("stiffness_estimator") != std::string::npos) {
              for (const auto& kv : s.values) diagnostics_[kv.key] = kv.value;
              status_message_ = s.message;
            }
        });
    spinner_.start();
    ASSERT_TRUE(waitWall(
        [this] {
          return torque_pub_.getNumSubscribers() > 0 && joints_pub_.getNumSubscribers() > 0 &&
                 calibration_sub_.getNumPublishers() > 0 &&
                 measured_te_sub_.getNumPublishers() > 0 && te_sub_.getNumPublishers() > 0 &&
                 period_sub_.getNumPublishers() > 0;
        },
        30.0))
        << "the node did not come up";
    ros::WallDuration(0.5).sleep();  // the TCP links settle after the master reports them
  }
  std::string diagnostic(const std::string& key) {
    std::lock_guard<std::mutex> l(m_);
    auto it = diagnostics_.find(key);
    return it == diagnostics_.end() ? "" : it->second;
  }
  /// The node has accepted `count` inputs of a kind (on /diagnostics, every ~diagnostic_period).
  bool accepted(const std::string& key, std::size_t count) {
    return waitWall([&] { return diagnostic(key) == std::to_string(count); }, 20.0);
  }

  /// Publishes each torque step, then its readings in chunks the subscriber queue holds, each
  /// waited for on /diagnostics, so the node sees exactly this order.
  void publishInOrder(const std::vector<std::vector<Input>>& segments) {
    std::size_t torques = 0, readings = 0;
    for (const auto& segment : segments) {
      for (std::size_t i = 0; i < segment.size(); ++i) {
        if (segment[i].torque) {
          torque_pub_.publish(segment[i].wrench);
          ASSERT_TRUE(accepted("accepted_torque", ++torques))
              << "torque " << torques << ": " << diagnostic("last_event");
          continue;
        }
        joints_pub_.publish(segment[i].joints);
        ++readings;
        if (readings % 500 == 0 || i + 1 == segment.size()) {
          ASSERT_TRUE(accepted("accepted_joint_states", readings))
              << readings << ": " << diagnostic("last_event");
        }
      }
    }
  }

  /// Every message the node published equals the in-process one (header.seq aside).
  void expectSameMessages(const CollectingSink& sink) {
    {
      std::lock_guard<std::mutex> l(m_);
      ASSERT_EQ(calibration_.size(), sink.calibrations.size());
      ASSERT_EQ(measured_te_.size(), sink.measured_tes.size());
      for (std::size_t i = 0; i < calibration_.size(); ++i) {
        drivetrain_stiffness::Calibration got = calibration_[i];
        got.header.seq = sink.calibrations[i].header.seq;
        EXPECT_TRUE(got == sink.calibrations[i])
            << "calibration[" << i << "]: " << got << "\nin-process:\n"
            << sink.calibrations[i];
      }
      std::size_t differ = 0;
      for (std::size_t i = 0; i < measured_te_.size(); ++i) {
        drivetrain_stiffness::MeasuredTe got = measured_te_[i];
        got.header.seq = sink.measured_tes[i].header.seq;
        if (!(got == sink.measured_tes[i]) && differ++ < 3) {
          ADD_FAILURE() << "measured_te[" << i << "]: " << got << "\nin-process:\n"
                        << sink.measured_tes[i];
        }
      }
      EXPECT_EQ(differ, 0u);
      // The dynamics driven by the encoders' phase and speed: the same bytes as in-process.
      ASSERT_EQ(te_.size(), sink.tes.size());
      ASSERT_EQ(periods_.size(), sink.periods.size());
      differ = 0;
      for (std::size_t i = 0; i < te_.size(); ++i) {
        drivetrain_stiffness::TransmissionError got = te_[i];
        got.header.seq = sink.tes[i].header.seq;
        if (!(got == sink.tes[i]) && differ++ < 3)
          ADD_FAILURE() << "transmission_error[" << i << "]: " << got << "\nin-process:\n"
                        << sink.tes[i];
      }
      for (std::size_t i = 0; i < periods_.size(); ++i) {
        drivetrain_stiffness::MeshPeriodStats got = periods_[i];
        got.header.seq = sink.periods[i].header.seq;
        if (!(got == sink.periods[i]) && differ++ < 6)
          ADD_FAILURE() << "mesh_period_stats[" << i << "]: " << got << "\nin-process:\n"
                        << sink.periods[i];
      }
      EXPECT_EQ(differ, 0u);
      std::map<std::string, int> seen;
      for (const auto& m : calibration_) ++seen[m.outcome];
      for (const auto& [outcome, n] : seen)
        std::cout << "calibration outcome '" << outcome << "': " << n << "\n";
      EXPECT_GT(seen["baseline"], 0);
    }
  }

  /// /diagnostics: the counters and the calibration's state, against the in-process calibrator.
  void expectCalibrationDiagnostics(const RigPipeline& pipeline, const CollectingSink& sink) {
    const CalibrationEstimate& e = pipeline.calibrator()->estimate();
    EXPECT_TRUE(waitWall(
        [&] {
          return diagnostic("calibration_published") == std::to_string(sink.calibrations.size());
        },
        5.0))
        << diagnostic("calibration_published");
    EXPECT_EQ(diagnostic("measured_te_published"), std::to_string(sink.measured_tes.size()));
    EXPECT_EQ(diagnostic("calibration_errors"), "0");
    EXPECT_EQ(diagnostic("calibration"), toString(e.outcome));
    EXPECT_EQ(diagnostic("calibration_windows"), std::to_string(e.windows));
    EXPECT_EQ(diagnostic("calibration_updates"), std::to_string(e.updates));
    EXPECT_EQ(diagnostic("calibration_gated"), std::to_string(e.gated));
    EXPECT_EQ(diagnostic("calibration_identified"), identifiedParameters(e));
    EXPECT_NE(diagnostic("calibration.mesh_stiffness_scale [-]"), "");
    // No window updated (the loaded ones are gated: no TE), so /diagnostics says why, the sentence
    // the in-process calibrator gives for the same inputs, with a WARN.
    ASSERT_EQ(e.updates, 0u);
    const std::string waiting = pipeline.calibrator()->waitingReason();
    std::cout << "calibration_waiting: " << waiting << "\n";
    EXPECT_NE(waiting.find("gated"), std::string::npos) << waiting;
    EXPECT_EQ(diagnostic("calibration_waiting"), waiting);
    EXPECT_TRUE(waitWall(
        [&] {
          std::lock_guard<std::mutex> l(m_);
          return status_message_.find("calibration waiting: " + waiting) != std::string::npos;
        },
        5.0))
        << status_message_;
    EXPECT_NE(diagnostic("calibration.te_offset [m]"), "");
  }

  /// With every input stopped and the encoders driving the phase, /diagnostics says how old the
  /// last reading is on the node's clock.
  void expectEncoderSilence() {
    EXPECT_EQ(diagnostic("phase_source"), "encoders");
    const double silence = std::stod(
        diagnostic("encoder_silence [s]").empty() ? "nan" : diagnostic("encoder_silence [s]"));
    const double expected =
        (ros::Time::now() - (ros::Time(kT0, 0) + ros::Duration(3.0 * kSegment))).toSec();
    // (diagnostic_updater prints about six significant digits: some 50 s at this age)
    EXPECT_NEAR(silence / expected, 1.0, 1e-5)
        << "the age of the last reading, 3 segments after kT0";
    EXPECT_TRUE(waitWall(
        [&] {
          std::lock_guard<std::mutex> l(m_);
          return status_message_.find("no joint_states for") != std::string::npos;
        },
        5.0))
        << status_message_;
  }

  ros::NodeHandle nh_;
  ros::AsyncSpinner spinner_{2};
  ros::Publisher torque_pub_, joints_pub_;
  ros::Subscriber calibration_sub_, measured_te_sub_, te_sub_, period_sub_, diag_sub_;
  std::mutex m_;
  std::vector<drivetrain_stiffness::Calibration> calibration_;
  std::vector<drivetrain_stiffness::MeasuredTe> measured_te_;
  std::vector<drivetrain_stiffness::TransmissionError> te_;
  std::vector<drivetrain_stiffness::MeshPeriodStats> periods_;
  std::map<std::string, std::string> diagnostics_;
  std::string status_message_;  ///< the last /diagnostics status line of the node
};

TEST_F(CalibrationTopicsTest, NodePublishesWhatThePipelineGivesInProcess) {
  // The node's own settings, read by the node's getter from its private namespace.
  const ros::NodeHandle node("/stiffness_estimator");
  std::string gearbox;
  ASSERT_TRUE(node.getParam("gearbox_config", gearbox));
  const auto get = [&node](const std::string& name, const auto& fallback) {
    return readParam(node, name, fallback);
  };
  const RigConfig rig = loadRigFile(gearbox);
  ASSERT_TRUE(rig.calibration.present);
  RigPipeline pipeline(rig, readPipelineOptions(get, rig), readRuntimeSettings(get, rig));
  ASSERT_NE(pipeline.calibrator(), nullptr);
  CollectingSink sink;
  const OutputSettings frames = readOutputSettings(get);
  sink.rig_frame = frames.frames.rig;
  sink.pinion_frame = frames.frames.pinion;
  const JointNames joints = readJointNames(get);
  const std::vector<std::vector<Input>> segments = makeSegments(rig, joints);
  feedInProcess(pipeline, segments, joints, sink);
  ASSERT_GT(sink.calibrations.size(), 3u);
  ASSERT_GT(sink.measured_tes.size(), 100u);
  ASSERT_GT(sink.tes.size(), 1000u);  // 1.1 s at the 1 kHz output rate
  ASSERT_GT(sink.periods.size(), 10u);

  // Before any input the calibration says it waits for its first reading; no WARN for that (a rig
  // without the gear encoder would warn every second).
  const std::string no_reading =
      "no encoder reading with the gear angle has reached the calibration";
  EXPECT_TRUE(waitWall([&] { return diagnostic("calibration_waiting") == no_reading; }, 5.0))
      << diagnostic("calibration_waiting");
  {
    std::lock_guard<std::mutex> l(m_);
    EXPECT_EQ(status_message_.find("calibration waiting"), std::string::npos) << status_message_;
  }

  publishInOrder(segments);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_TRUE(waitWall(
      [&] {
        std::lock_guard<std::mutex> l(m_);
        return calibration_.size() >= sink.calibrations.size() &&
               measured_te_.size() >= sink.measured_tes.size() && te_.size() >= sink.tes.size() &&
               periods_.size() >= sink.periods.size();
      },
      20.0));
  expectSameMessages(sink);
  ASSERT_FALSE(HasFatalFailure());
  expectCalibrationDiagnostics(pipeline, sink);
  ASSERT_FALSE(HasFatalFailure());
  expectEncoderSilence();
}

}  // namespace
}  // namespace drivetrain_stiffness

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "calibration_topics_rostest");
  return RUN_ALL_TESTS();
}

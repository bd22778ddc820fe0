// The node's modal identification on the graph (docs/vibration.md "Identification in the
// pipeline"): one torque input, then 3.2 s of accelerometer blocks (2 channels at 51.2 kHz, the
// rig's two transverse modes moved, exactly discretised oscillators:
// test/modal/synthetic_modes.hpp) on `vibration`. The node identifies on its worker thread; every
// modal_identification and calibration message equals, bit for bit (header.seq aside), what the
// same RigPipeline gives in-process, identifying in the caller's thread, for the same inputs in the
// same order: the node against the replay with vibration. /diagnostics counts the identifications.
#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <mutex>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>

#include "drivetrain_stiffness/VibrationBlock.h"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/ros/message_conversion.hpp"
#include "drivetrain_stiffness/ros/node_parameters.hpp"
#include "drivetrain_stiffness/ros/parameters.hpp"
#include "synthetic_modes.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

const std::uint32_t kT0 = 1767225600;  // the stamps' epoch [s]
constexpr double kRate = 51200.0;      // [Hz]
constexpr std::size_t kBlock = 1024;   // frames per block
constexpr int kBlocks = 160;           // 3.2 s

bool waitWall(const std::function<bool()>& done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

struct CollectingSink : PipelineSink {
  std::string rig_frame, pinion_frame;
  std::vector<drivetrain_stiffness::ModalIdentification> modal;
  std::vector<drivetrain_stiffness::Calibration> calibrations;
  void modalIdentification(Stamp stamp, const ModalReport& r) override {
    modal.push_back(toModalIdentificationMsg(stamp, pinion_frame, r));
  }
  void calibration(Stamp stamp, const CalibrationEstimate& e) override {
    calibrations.push_back(toCalibrationMsg(stamp, rig_frame, e));
  }
};

/// The blocks: the gear mode at 7,800 Hz, the pinion mode at 9,200 Hz, each mostly on its own
/// shaft's housing.
std::vector<drivetrain_stiffness::VibrationBlock> makeBlocks() {
  Eigen::MatrixXd shapes(2, 2);
  shapes << 0.2, 1.0, 1.0, -0.1;
  const modal::test::SyntheticModes modes({{7800.0, 0.02}, {9200.0, 0.02}}, shapes, kRate);
  const Eigen::MatrixXd y = modes.record(kBlocks * kBlock, 17);
  std::vector<drivetrain_stiffness::VibrationBlock> blocks(kBlocks);
  for (int b = 0; b < kBlocks; ++b) {
    auto& m = blocks[b];
    m.header.stamp = ros::Time(kT0, 0) + ros::Duration(b * kBlock / kRate);
    m.header.seq = static_cast<std::uint32_t>(b + 1);
    m.sample_rate = kRate;
    m.channels = {"pinion_bearing", "gear_bearing"};
    m.data.resize(2 * kBlock);
    for (std::size_t i = 0; i < kBlock; ++i)
      for (int c = 0; c < 2; ++c)
        m.data[2 * i + c] = static_cast<float>(y(c, b * static_cast<long>(kBlock) + i));
  }
  return blocks;
}

class ModalTopicsTest : public testing::Test {
 protected:
  void SetUp() override {
    torque_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>("torque", 10);
    vibration_pub_ = nh_.advertise<drivetrain_stiffness::VibrationBlock>("vibration", 200);
    modal_sub_ = nh_.subscribe<drivetrain_stiffness::ModalIdentification>(
        "modal_identification", 100,
        [this](const drivetrain_stiffness::ModalIdentification::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          modal_.push_back(*m);
        });
    calibration_sub_ = nh_.subscribe<drivetrain_stiffness::Calibration>(
        "calibration", 100, [this](const drivetrain_stiffness::Calibration::ConstPtr& m) {
          std::lock_guard<std::mutex> l(m_);
          calibration_.push_back(*m);
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
          return torque_pub_.getNumSubscribers() > 0 && vibration_pub_.getNumSubscribers() > 0 &&
                 modal_sub_.getNumPublishers() > 0 && calibration_sub_.getNumPublishers() > 0;
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
  bool accepted(const std::string& key, std::size_t count) {
    return waitWall([&] { return diagnostic(key) == std::to_string(count); }, 20.0);
  }
  /// Every message the node published equals the in-process one (header.seq aside).
  void expectSame(const CollectingSink& sink);

  ros::NodeHandle nh_;
  ros::AsyncSpinner spinner_{2};
  ros::Publisher torque_pub_, vibration_pub_;
  ros::Subscriber modal_sub_, calibration_sub_, diag_sub_;
  std::mutex m_;
  std::vector<drivetrain_stiffness::ModalIdentification> modal_;
  std::vector<drivetrain_stiffness::Calibration> calibration_;
  std::map<std::string, std::string> diagnostics_;
};

TEST_F(ModalTopicsTest, NodePublishesWhatThePipelineGivesInProcess) {
  const ros::NodeHandle node("/stiffness_estimator");
  std::string gearbox;
  ASSERT_TRUE(node.getParam("gearbox_config", gearbox));
  const auto get = [&node](const std::string& name, const auto& fallback) {
    return readParam(node, name, fallback);
  };
  const RigConfig rig = loadRigFile(gearbox);
  PipelineOptions options = readPipelineOptions(get, rig);
  ASSERT_FALSE(options.modal_worker);  // in-process: the caller's thread; the node: a worker
  RigPipeline pipeline(rig, options, readRuntimeSettings(get, rig));
  CollectingSink sink;
  const OutputSettings frames = readOutputSettings(get);
  sink.rig_frame = frames.frames.rig;
  sink.pinion_frame = frames.frames.pinion;

  geometry_msgs::WrenchStamped torque;
  torque.header.stamp = ros::Time(kT0, 0);
  torque.header.frame_id = "pinion";
  torque.wrench.torque.z = 0.5;
  const std::vector<drivetrain_stiffness::VibrationBlock> blocks = makeBlocks();
  pipeline.torque(fromRosTime(torque.header.stamp), 0.5, sink, {"", 0, "pinion"});
  for (const auto& m : blocks) {
    const VibrationBlockView view{m.sample_rate, m.channels.data(), m.channels.size(),
                                  m.data.data(), m.data.size()};
    ASSERT_EQ(pipeline.vibration(fromRosTime(m.header.stamp), view, sink, {"", m.header.seq, ""}),
              InputOutcome::kAccepted);
  }
  // Records end at 1 s, 2 s and 3 s; the first two are applied 0.5 s later, in the stream.
  ASSERT_EQ(sink.modal.size(), 2u);
  ASSERT_EQ(pipeline.counters().modal_out, 2u);

  torque_pub_.publish(torque);
  ASSERT_TRUE(accepted("accepted_torque", 1)) << diagnostic("last_event");
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    vibration_pub_.publish(blocks[b]);
    if ((b + 1) % 50 == 0 || b + 1 == blocks.size()) {
      ASSERT_TRUE(accepted("accepted_vibration", b + 1)) << b << ": " << diagnostic("last_event");
    }
  }
  ASSERT_TRUE(waitWall(
      [&] {
        std::lock_guard<std::mutex> l(m_);
        return modal_.size() >= sink.modal.size() &&
               calibration_.size() >= sink.calibrations.size();
      },
      20.0));
  expectSame(sink);
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_TRUE(waitWall([&] { return diagnostic("modal_identifications_published") == "2"; }, 5.0))
      << diagnostic("modal_identifications_published");
  EXPECT_EQ(diagnostic("modal_identification_errors"), "0");
}

void ModalTopicsTest::expectSame(const CollectingSink& sink) {
  std::lock_guard<std::mutex> l(m_);
  ASSERT_EQ(modal_.size(), sink.modal.size());
  for (std::size_t i = 0; i < modal_.size(); ++i) {
    drivetrain_stiffness::ModalIdentification got = modal_[i];
    got.header.seq = sink.modal[i].header.seq;
    EXPECT_TRUE(got == sink.modal[i]) << "modal_identification[" << i << "]";
    ASSERT_GE(got.modes.size(), 2u);
  }
  ASSERT_EQ(calibration_.size(), sink.calibrations.size());
  for (std::size_t i = 0; i < calibration_.size(); ++i) {
    drivetrain_stiffness::Calibration got = calibration_[i];
    got.header.seq = sink.calibrations[i].header.seq;
    EXPECT_TRUE(got == sink.calibrations[i]) << "calibration[" << i << "]";
  }
}

}  // namespace
}  // namespace drivetrain_stiffness

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "modal_topics_rostest");
  return RUN_ALL_TESTS();
}

// Graph-level test of the stiffness_estimator node: good inputs give the core library's answer
// with the input's header; NaN, negative and absurd inputs are rejected, counted on /diagnostics,
// and do not disturb the next good answer.
#include <gtest/gtest.h>

#include <cmath>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>

#include "drivetrain_stiffness/MeshPeriodStats.h"
#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/Resonance.h"
#include "drivetrain_stiffness/SpectralPeaks.h"
#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

using namespace drivetrain_stiffness;

class NodeTest : public testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle pnh("~");
    ASSERT_TRUE(pnh.getParam("gearbox_config", path_));
    reference_ = std::make_unique<StiffnessEstimator>(loadRigFile(path_));
    stiffness_sub_ = nh_.subscribe<Stiffness>(
        "stiffness", 100, [this](const Stiffness::ConstPtr& m) { received_.push_back(*m); });
    diag_sub_ = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
          diagnostics_.push_back(*m);
        });
    spectrum_sub_ = nh_.subscribe<SpectralPeaks>(
        "te_spectrum", 100, [this](const SpectralPeaks::ConstPtr& m) { spectra_.push_back(*m); });
    resonance_sub_ = nh_.subscribe<Resonance>(
        "resonance", 100, [this](const Resonance::ConstPtr& m) { resonance_.push_back(*m); });
    te_sub_ = nh_.subscribe<TransmissionError>(
        "transmission_error", 10000,
        [this](const TransmissionError::ConstPtr& m) { te_.push_back(*m); });
    mesh_period_sub_ = nh_.subscribe<MeshPeriodStats>(
        "mesh_period_stats", 1000,
        [this](const MeshPeriodStats::ConstPtr& m) { mesh_periods_.push_back(*m); });
    torque_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>("torque", 10);
    preload_pub_ = nh_.advertise<Preload>("preload", 10);
    ASSERT_TRUE(waitFor(
        [&] {
          return torque_pub_.getNumSubscribers() > 0 && preload_pub_.getNumSubscribers() > 0 &&
                 stiffness_sub_.getNumPublishers() > 0;
        },
        20.0));
  }

  template <typename F>
  bool waitFor(F done, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::ok() && ros::WallTime::now() < end) {
      ros::spinOnce();
      if (done()) return true;
      ros::WallDuration(0.005).sleep();
    }
    return done();
  }

  void sendTorque(double torque, double stamp) {
    geometry_msgs::WrenchStamped m;
    m.header.stamp = ros::Time(stamp);
    m.header.frame_id = "pinion";
    m.wrench.torque.z = torque;
    torque_pub_.publish(m);
  }

  Preload preload(double stamp, double axial, double radial, double inner, double outer) {
    Preload m;
    m.header.stamp = ros::Time(stamp);
    for (const char* name : {"pinion_bearing", "gear_bearing"}) {
      BearingPreload b;
      b.name = name;
      b.axial_preload = axial;
      b.radial_preload = radial;
      b.inner_interference = inner;
      b.outer_interference = outer;
      m.bearings.push_back(b);
    }
    return m;
  }

  // Expects exactly one new stiffness message, stamped `stamp`, equal to the reference estimate.
  void expectAnswer(double stamp, const StiffnessEstimate& expected) {
    const std::size_t before = received_.size();
    ASSERT_TRUE(waitFor([&] { return received_.size() > before; }, 60.0))
        << "no stiffness for stamp " << stamp;
    const Stiffness& s = received_.back();
    EXPECT_DOUBLE_EQ(s.header.stamp.toSec(), stamp);
    ASSERT_EQ(s.bearings.size(), expected.supports.size());
    for (std::size_t i = 0; i < s.bearings.size(); ++i) {
      const double k = expected.supports[i].solution.radialStiffness();
      EXPECT_NEAR(s.bearings[i].radial_stiffness, k, 1e-9 * k) << s.bearings[i].name;
      EXPECT_TRUE(std::isfinite(s.bearings[i].radial_stiffness));
      for (double v : s.bearings[i].stiffness_matrix) EXPECT_TRUE(std::isfinite(v));
    }
    EXPECT_NEAR(s.mesh_phase, expected.mesh.phase, 1e-9);
    EXPECT_NEAR(s.mesh_stiffness, expected.mesh.current.composite,
                1e-6 * expected.mesh.current.composite);
    EXPECT_NEAR(s.mesh_stiffness_mean, expected.mesh.mean, 1e-6 * expected.mesh.mean);
    EXPECT_TRUE(s.drive_flank_loaded);
    EXPECT_TRUE(s.back_flank_loaded);  // 0.5 N m is far inside the anti-backlash preload window
    EXPECT_GT(s.mesh_stiffness, 5e7);
  }

  // Waits for a diagnostics status whose key `key` reaches at least `count`.
  bool diagnosticCountAtLeast(const std::string& key, int count) {
    return waitFor(
        [&] {
          for (const auto& array : diagnostics_)
            for (const auto& status : array.status)
              for (const auto& kv : status.values)
                if (kv.key == key && std::stoi(kv.value) >= count) return true;
          return false;
        },
        60.0);
  }

  bool noMessageFor(double seconds) {
    const std::size_t before = received_.size();
    waitFor([] { return false; }, seconds);
    return received_.size() == before;
  }

  static std::array<double, 2> shaftStiffness(const StiffnessEstimator& e) {
    std::array<double, 2> k{{0.0, 0.0}};
    for (std::size_t i = 0; i < e.current().supports.size(); ++i)
      k[e.rig().bearings[i].shaft] += e.current().supports[i].solution.radialStiffness();
    return k;
  }

  /// 1b. A resonance estimate came with the first answer: three finite modes, the torsional one
  /// (dominated by x) near 60 kHz with the seed's masses, and a stable Floquet margin.
  void expectResonance() {
    ASSERT_TRUE(waitFor([&] { return !resonance_.empty(); }, 60.0));
    const Resonance& res = resonance_.back();
    ASSERT_EQ(res.frequencies_hz.size(), 3u);
    for (double f : res.frequencies_hz) EXPECT_TRUE(std::isfinite(f) && f > 0.0);
    EXPECT_EQ(res.dominant_coordinate[2], "x");
    EXPECT_NEAR(res.frequencies_hz[2], 60e3, 10e3);
    EXPECT_TRUE(res.floquet_valid);
    EXPECT_GT(res.floquet_margin, 0.0);
  }

  /// 2. NaN torque, absurd torque, negative and NaN preload, unknown bearing: no output, counted.
  void expectBadInputRefused() {
    sendTorque(std::nan(""), 12.0);
    sendTorque(1e9, 12.1);
    preload_pub_.publish(preload(12.2, -5.0, 800.0, 5e-6, 5e-6));
    preload_pub_.publish(preload(12.3, 1200.0, std::nan(""), 5e-6, 5e-6));
    Preload unknown = preload(12.4, 1200.0, 800.0, 5e-6, 5e-6);
    unknown.bearings[0].name = "no_such_bearing";
    preload_pub_.publish(unknown);
    EXPECT_TRUE(noMessageFor(0.5));
    EXPECT_TRUE(diagnosticCountAtLeast("rejected_torque", 2));
    EXPECT_TRUE(diagnosticCountAtLeast("rejected_preload", 3));
    bool warned = false;
    for (const auto& array : diagnostics_)
      for (const auto& status : array.status)
        warned |= status.level == diagnostic_msgs::DiagnosticStatus::WARN &&
                  status.message.find("rejected") != std::string::npos;
    EXPECT_TRUE(warned);
  }

  /// 4. Dynamics: the first torque (t = 11) started the model; the torque at 13.0137 s released
  /// every 1 ms sample in (11, 13.0137] with the 0.5 N m held: 2013 transmission_error messages,
  /// stamped on the grid, equal to what the core class gives when every accepted input first hands
  /// over `stiffness_after_input` (preload at 10 s, torque 0.5 N m at 11 s, which also starts the
  /// model, torque 0.25 N m at 13.0137 s) and then the model advances.
  void expectDynamicsReplayed(const std::vector<std::array<double, 2>>& stiffness_after_input) {
    ASSERT_TRUE(waitFor([&] { return te_.size() >= 2013; }, 60.0)) << te_.size();
    EXPECT_EQ(te_.size(), 2013u);
    EXPECT_NEAR(te_.front().header.stamp.toSec(), 11.001, 1e-6);
    EXPECT_NEAR(te_.back().header.stamp.toSec(), 13.013, 1e-6);
    for (const TransmissionError& m : te_) {
      EXPECT_TRUE(std::isfinite(m.dynamic_te) && std::isfinite(m.x) && std::isfinite(m.mesh_force));
      EXPECT_TRUE(m.drive_flank_loaded && m.back_flank_loaded);
      EXPECT_DOUBLE_EQ(m.torque, 0.5);
    }
    // The core class, built with the bearing stiffness at start-up (configured preloads, no
    // torque).
    const RigConfig rig = loadRigFile(path_);
    DynamicsEstimator replay(rig, shaftStiffness(StiffnessEstimator(rig)), 1000.0);
    replay.setBearingStiffness(stiffness_after_input[0]);
    replay.setBearingStiffness(stiffness_after_input[1]);
    replay.reset(11.0, 0.5);
    replay.setBearingStiffness(stiffness_after_input[2]);
    std::vector<DynamicsSample> expected;
    replay.advanceTo(13.0137, [&](const DynamicsSample& d) { expected.push_back(d); });
    ASSERT_EQ(expected.size(), te_.size());
    for (std::size_t i = 0; i < te_.size(); ++i) {
      EXPECT_NEAR(te_[i].dynamic_te, expected[i].dynamic_te,
                  1e-12 * std::abs(expected[i].dynamic_te) + 1e-18)
          << i;
      EXPECT_NEAR(te_[i].mesh_force, expected[i].mesh_force,
                  1e-9 * std::abs(expected[i].mesh_force) + 1e-12)
          << i;
    }
    EXPECT_TRUE(diagnosticCountAtLeast("transmission_error_published", 2013));
  }

  /// Sliding spectrum of the predicted TE (1024-sample window, hop 256): updates after 1024, 1280,
  /// 1536, 1792 samples; the mesh frequency 1000 rpm * 20 / 60 = 333.3 Hz (where the TE excitation
  /// sits) is among the three peaks.
  void expectSpectra() {
    ASSERT_TRUE(waitFor([&] { return spectra_.size() >= 4; }, 60.0)) << spectra_.size();
    EXPECT_EQ(spectra_.size(), 4u);
    bool mesh_peak = false;
    for (double f : spectra_.back().frequencies_hz)
      mesh_peak |= std::abs(f - 1000.0 * 20 / 60) < spectra_.back().resolution_hz;
    EXPECT_TRUE(mesh_peak);
  }

  /// Per-mesh-period statistics: from the first sample on a tooth switch (11.003 s) blocks of 4
  /// periods (12 samples, 12 ms) up to 13.013 s: 167 blocks; the mean mesh force T / r_b,p.
  void expectMeshPeriods() {
    ASSERT_TRUE(waitFor([&] { return mesh_periods_.size() >= 167; }, 60.0)) << mesh_periods_.size();
    EXPECT_EQ(mesh_periods_.size(), 167u);
    const double mean_force = 0.5 / reference_->mesh().geometry().baseRadius(0);
    for (std::size_t i = 0; i < mesh_periods_.size(); ++i) {
      const MeshPeriodStats& b = mesh_periods_[i];
      EXPECT_NEAR(b.header.stamp.toSec(), 11.015 + 0.012 * static_cast<double>(i), 1e-6) << i;
      EXPECT_EQ(b.periods, 4u);
      EXPECT_EQ(b.samples, 12u);
      EXPECT_NEAR(b.mesh_frequency, 1000.0 * 20 / 60, 1e-3 * 1000.0 * 20 / 60);
      EXPECT_TRUE(std::isfinite(b.te_mean) && std::isfinite(b.te_rms) &&
                  std::isfinite(b.mesh_force_rms));
      if (b.header.stamp.toSec() > 11.3) {
        EXPECT_NEAR(b.mesh_force_mean, mean_force, 1e-2 * mean_force) << i;
      }
    }
    EXPECT_TRUE(diagnosticCountAtLeast("mesh_period_stats_published", 167));
  }

  ros::NodeHandle nh_;
  std::string path_;
  std::unique_ptr<StiffnessEstimator> reference_;
  ros::Subscriber stiffness_sub_, diag_sub_, te_sub_, resonance_sub_, spectrum_sub_;
  std::vector<SpectralPeaks> spectra_;
  std::vector<Resonance> resonance_;
  std::vector<TransmissionError> te_;
  std::vector<MeshPeriodStats> mesh_periods_;
  ros::Subscriber mesh_period_sub_;
  ros::Publisher torque_pub_, preload_pub_;
  std::vector<Stiffness> received_;
  std::vector<diagnostic_msgs::DiagnosticArray> diagnostics_;
};

TEST_F(NodeTest, AnswersGoodInputAndSurvivesBadInput) {
  // 1. Preload then torque: the node's answer equals the core library's.
  preload_pub_.publish(preload(10.0, 1200.0, 800.0, 5e-6, 5e-6));
  reference_->setPreloads(
      {{"pinion_bearing", 1200.0, 800.0, 5e-6, 5e-6}, {"gear_bearing", 1200.0, 800.0, 5e-6, 5e-6}});
  expectAnswer(10.0, reference_->current());
  std::vector<std::array<double, 2>> stiffness_after_input = {shaftStiffness(*reference_)};
  // The node's pinion angle is omega (t - t0), t0 = the first torque stamp, omega =
  // ~pinion_speed_rpm.
  const double omega = 1000.0 * 2 * M_PI / 60;
  sendTorque(0.5, 11.0);
  expectAnswer(11.0, reference_->setTorque(0.5, 0.0));
  stiffness_after_input.push_back(shaftStiffness(*reference_));

  expectResonance();
  ASSERT_FALSE(HasFatalFailure());

  expectBadInputRefused();

  // 3. The next good input is answered correctly: state was not poisoned.
  sendTorque(0.25, 13.0137);
  expectAnswer(13.0137, reference_->setTorque(0.25, omega * 2.0137));
  stiffness_after_input.push_back(shaftStiffness(*reference_));

  expectDynamicsReplayed(stiffness_after_input);
  ASSERT_FALSE(HasFatalFailure());
  expectSpectra();
  ASSERT_FALSE(HasFatalFailure());
  expectMeshPeriods();
  ASSERT_FALSE(HasFatalFailure());

  // 5. A gap beyond ~max_gap (5 s here) restarts the dynamics instead of integrating it: the
  // stiffness answer still comes, no transmission_error sample is released, and the restart is
  // counted.
  const std::size_t te_before = te_.size();
  sendTorque(0.3, 23.5);
  expectAnswer(23.5, reference_->setTorque(0.3, omega * 12.5));
  EXPECT_TRUE(diagnosticCountAtLeast("gap_restarts", 1));
  EXPECT_EQ(te_.size(), te_before);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "stiffness_estimator_rostest");
  return RUN_ALL_TESTS();
}

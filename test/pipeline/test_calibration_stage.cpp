// CalibrationStage: a Calibrator only when enabled on a rig with calibration and dynamics blocks;
// without one the sink's bands are the drawing's model with bounds of zero width; with one they
// are the calibrator's, and a reading goes to it.
#include <gtest/gtest.h>

#include <memory>

#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

std::shared_ptr<const RigConfig> seed() { return std::make_shared<RigConfig>(test::seedServo()); }

}  // namespace

TEST(CalibrationStage, CalibratesOnlyWhenEnabledWithBothBlocks) {
  const auto rig = seed();
  ASSERT_TRUE(rig->calibration.present && rig->dynamics.present);
  StiffnessEstimator estimator(rig);
  EXPECT_NE(CalibrationStage(rig, estimator, true).calibrator(), nullptr);
  EXPECT_EQ(CalibrationStage(rig, estimator, false).calibrator(), nullptr);
  auto bare = std::make_shared<RigConfig>(*rig);
  bare->calibration.present = false;
  EXPECT_EQ(CalibrationStage(bare, estimator, true).calibrator(), nullptr);
  auto still = std::make_shared<RigConfig>(*rig);
  still->dynamics.present = false;
  EXPECT_EQ(CalibrationStage(still, estimator, true).calibrator(), nullptr);
}

TEST(CalibrationStage, WithoutACalibrationTheBandsAreTheDrawingsOfZeroWidth) {
  const auto rig = seed();
  StiffnessEstimator estimator(rig);
  CalibrationStage stage(rig, estimator, false);
  const StiffnessEstimate& e = estimator.setTorque(0.1, 0.0);
  const CalibrationBands b = stage.stiffnessBands(e);
  EXPECT_EQ(b.mesh_stiffness, e.mesh.mean);
  EXPECT_EQ(b.mesh_stiffness_low, e.mesh.mean);
  EXPECT_EQ(b.mesh_stiffness_high, e.mesh.mean);
  EXPECT_EQ(b.bearing_stiffness, estimator.shaftRadialStiffness());
  EXPECT_EQ(b.bearing_stiffness_low, b.bearing_stiffness_high);
  ResonanceEstimate r;
  for (std::size_t i = 0; i < r.modes.size(); ++i) r.modes[i].natural_frequency = 100.0 * (i + 1);
  const CalibrationBands rb = stage.resonanceBands(r);
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    EXPECT_EQ(rb.natural_frequency[i], 100.0 * (i + 1));
    EXPECT_EQ(rb.natural_frequency_low[i], rb.natural_frequency_high[i]);
  }
}

TEST(CalibrationStage, WithACalibrationTheBandsAreTheCalibratorsAndReadingsReachIt) {
  const auto rig = seed();
  StiffnessEstimator estimator(rig);
  CalibrationStage stage(rig, estimator, true);
  const StiffnessEstimate& e = estimator.setTorque(0.1, 0.0);
  const CalibrationBands expected = stage.calibrator()->bands(e.torque, estimator, false);
  const CalibrationBands b = stage.stiffnessBands(e);
  EXPECT_EQ(b.mesh_stiffness, expected.mesh_stiffness);
  EXPECT_EQ(b.mesh_stiffness_low, expected.mesh_stiffness_low);
  EXPECT_EQ(b.mesh_stiffness_high, expected.mesh_stiffness_high);
  PipelineSink sink;
  // Readings before any baseline publish nothing and fail nothing.
  for (int k = 0; k < 10; ++k) {
    stage.reading(test::stampAt(k * 2e-4), 0.01 * k, -0.01 * k * 20 / 40.0, 0.0, 50.0, 0.0, k > 0,
                  sink);
  }
  EXPECT_EQ(stage.counters().calibration_errors, 0u) << stage.events().last();
  EXPECT_EQ(stage.counters().measured_te_out, 0u);
}

// ResonanceTracker: the Courant-Fischer shortcut's bounds, the first update publishing, a
// stiffness inside the bounds skipping the modal analysis, and the published frequencies equal to
// a modal analysis of the same operating point.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "drivetrain_stiffness/pipeline/resonance_tracker.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

struct Resonances : PipelineSink {
  std::vector<ResonanceEstimate> out;
  std::vector<CalibrationBands> bands;
  void resonance(Stamp, const ResonanceEstimate& r, const CalibrationBands& b) override {
    out.push_back(r);
    bands.push_back(b);
  }
};

struct Fixture {
  std::shared_ptr<const RigConfig> rig = std::make_shared<RigConfig>(test::seedServo());
  StiffnessEstimator estimator{rig};
  CalibrationStage calibration{rig, estimator, false};
  ResonanceTracker tracker{*rig, estimator, calibration, 0.01};
  const ResonanceCounters& counters = tracker.counters();
  DynamicsEstimator dynamics{rig, estimator.shaftRadialStiffness(), 1000.0, estimator.sharedMesh()};
  DampingRatios damping = DampingRatios::of(rig->dynamics);
  Resonances sink;
};

}  // namespace

TEST(ResonanceTracker, CourantFischerBoundsAreTheSquaredFactors) {
  const std::array<double, 3> at{1e8, 2e8, 3e8};
  EXPECT_TRUE(ResonanceTracker::withinCourantFischerBounds(at, at, 0.01));
  EXPECT_TRUE(ResonanceTracker::withinCourantFischerBounds({1e8 * 1.0199, 2e8, 3e8}, at, 0.01));
  EXPECT_FALSE(ResonanceTracker::withinCourantFischerBounds({1e8 * 1.0202, 2e8, 3e8}, at, 0.01));
  EXPECT_TRUE(ResonanceTracker::withinCourantFischerBounds({1e8, 2e8, 3e8 * 0.9802}, at, 0.01));
  EXPECT_FALSE(ResonanceTracker::withinCourantFischerBounds({1e8, 2e8, 3e8 * 0.9800}, at, 0.01));
}

TEST(ResonanceTracker, TheFirstUpdatePublishesTheModesOfTheOperatingPoint) {
  Fixture f;
  const StiffnessEstimate& e = f.estimator.setTorque(0.1, 0.0);
  f.tracker.update(test::stampAt(0.0), e, f.damping, f.dynamics, f.sink);
  ASSERT_EQ(f.sink.out.size(), 1u);
  ASSERT_TRUE(f.tracker.last().has_value());
  const auto modes = modalAnalysis(
      rigRotorParameters(*f.rig, f.estimator.mesh(), f.estimator.shaftRadialStiffness(), f.damping),
      e.mesh.mean);
  for (std::size_t i = 0; i < modes.size(); ++i) {
    EXPECT_EQ(f.sink.out[0].modes[i].natural_frequency, modes[i].natural_frequency);
    // Without a calibration the bands are the estimate's frequencies, of zero width.
    EXPECT_EQ(f.sink.bands[0].natural_frequency_low[i], modes[i].natural_frequency);
    EXPECT_EQ(f.sink.bands[0].natural_frequency_high[i], modes[i].natural_frequency);
  }
  EXPECT_EQ(f.counters.modal_updates, 1u);
  EXPECT_EQ(f.counters.resonance_out, 1u);
}

TEST(ResonanceTracker, AnUnchangedOperatingPointRunsNoAnalysisUntilForgotten) {
  Fixture f;
  const StiffnessEstimate& e = f.estimator.setTorque(0.1, 0.0);
  f.tracker.update(test::stampAt(0.0), e, f.damping, f.dynamics, f.sink);
  f.tracker.update(test::stampAt(0.001), e, f.damping, f.dynamics, f.sink);
  EXPECT_EQ(f.counters.modal_updates, 1u);
  EXPECT_EQ(f.sink.out.size(), 1u);
  f.tracker.forget();
  EXPECT_FALSE(f.tracker.last().has_value());
  f.tracker.update(test::stampAt(0.002), e, f.damping, f.dynamics, f.sink);
  EXPECT_EQ(f.counters.modal_updates, 2u);
  EXPECT_EQ(f.sink.out.size(), 2u);
}

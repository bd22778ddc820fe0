// One rig and one mesh table for the whole pipeline: the stiffness estimator, the dynamics and the
// calibration read the same RigConfig and the same AntiBacklashMesh, shared read only; what
// changes at run time (the damping of the settings) lives beside the rig, not in copies of it.
#include <gtest/gtest.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() {  // with dynamics and calibration blocks
  static const RigConfig r =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  return r;
}

constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;  // 2026-01-01
Stamp at(double seconds) { return Stamp{kEpoch + std::llround(seconds * 1e9)}; }

struct LastResonance : PipelineSink {
  std::optional<ResonanceEstimate> last;
  void resonance(Stamp, const ResonanceEstimate& r, const CalibrationBands&) override { last = r; }
};

ResonanceEstimate resonanceAfterOneTorque(RigPipeline& p) {
  LastResonance sink;
  EXPECT_EQ(p.torque(at(0.0), 0.1, sink), InputOutcome::kAccepted) << p.counters().last_event;
  EXPECT_TRUE(sink.last.has_value());
  return sink.last.value_or(ResonanceEstimate{});
}

}  // namespace

TEST(SharedRig, OneRigAndOneMeshTableForThePipeline) {
  ASSERT_TRUE(rig().calibration.present && rig().dynamics.present &&
              rig().mesh_stiffness_scale == 1.0);
  RigPipeline p(rig(), PipelineOptions{});
  ASSERT_NE(p.dynamics(), nullptr);
  ASSERT_NE(p.calibrator(), nullptr);
  EXPECT_EQ(&p.estimator().rig(), &p.rig());
  EXPECT_EQ(&p.dynamics()->rig(), &p.rig());
  EXPECT_EQ(&p.calibrator()->rig(), &p.rig());
  // The calibration's drawing-scale table is the estimator's (scale 1), as is the dynamics'.
  EXPECT_EQ(&p.calibrator()->teModel().unitMesh(), &p.estimator().mesh());
  EXPECT_EQ(&p.dynamics()->mesh(), &p.estimator().mesh());
  EXPECT_EQ(p.rig().dynamics.speed_rpm,
            PipelineOptions{}.pinion_speed_rpm);  // the options' speed, set once
}

TEST(SharedRig, RunTimeDampingActsAsIfGivenAtStartAndLeavesTheRigAlone) {
  const double start = rig().dynamics.mesh_damping_ratio;
  const double changed = start == 0.09 ? 0.08 : 0.09;
  RigPipeline reconfigured(rig(), PipelineOptions{});
  RuntimeSettings s = reconfigured.settings();
  s.mesh_damping_ratio = changed;
  reconfigured.apply(s);
  EXPECT_EQ(reconfigured.rig().dynamics.mesh_damping_ratio, start);  // the shared rig is read only
  EXPECT_EQ(reconfigured.dynamics()->damping().mesh, changed);
  const ResonanceEstimate after = resonanceAfterOneTorque(reconfigured);

  RigPipeline from_start(rig(), PipelineOptions{}, s);
  const ResonanceEstimate given = resonanceAfterOneTorque(from_start);
  RigPipeline unchanged(rig(), PipelineOptions{});
  const ResonanceEstimate before = resonanceAfterOneTorque(unchanged);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(after.modes[i].damping_ratio, given.modes[i].damping_ratio) << i;
    EXPECT_EQ(after.modes[i].natural_frequency, given.modes[i].natural_frequency) << i;
  }
  // And the change is seen: the torsional mode's damping moved with the mesh's ratio.
  bool moved = false;
  for (int i = 0; i < 3; ++i)
    moved = moved || after.modes[i].damping_ratio != before.modes[i].damping_ratio;
  EXPECT_TRUE(moved);
}

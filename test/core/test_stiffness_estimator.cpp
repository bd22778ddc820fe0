// StiffnessEstimator on its own: a reset estimator is indistinguishable from a freshly built one
// (the pipeline resets it on every clock or stamp jump, and the run after the jump must not depend
// on the run before it).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

const RigConfig& rig() { return test::seedServo(); }

std::vector<PreloadSetting> preloads(double axial) {
  return {{"pinion_bearing", axial, 1000.0, 0.0, 0.0}, {"gear_bearing", axial, 1000.0, 0.0, 0.0}};
}

// Bit for bit: the same inputs on the same state give the same doubles.
void expectSame(const StiffnessEstimate& a, const StiffnessEstimate& b) {
  EXPECT_EQ(a.torque, b.torque);
  EXPECT_EQ(a.mesh_force, b.mesh_force);
  EXPECT_EQ(a.mesh.phase, b.mesh.phase);
  EXPECT_EQ(a.mesh.current.composite, b.mesh.current.composite);
  EXPECT_EQ(a.mesh.mean, b.mesh.mean);
  ASSERT_EQ(a.supports.size(), b.supports.size());
  for (std::size_t i = 0; i < a.supports.size(); ++i) {
    EXPECT_EQ(a.supports[i].radial_load, b.supports[i].radial_load);
    EXPECT_EQ(a.supports[i].axial_load, b.supports[i].axial_load);
    EXPECT_TRUE(a.supports[i].solution.stiffness == b.supports[i].solution.stiffness)
        << a.supports[i].name;
    EXPECT_TRUE(a.supports[i].solution.displacement == b.supports[i].solution.displacement)
        << a.supports[i].name;
  }
}

}  // namespace

TEST(StiffnessEstimator, ResetEstimatorBehavesAsAFreshOne) {
  // A preload input is solved at the mesh phase of the last torque input's pinion angle. Before any
  // torque that angle is 0; a reset must bring it back to 0, or the first preload after a reset
  // reports the phase (and, on a switch, the mesh stiffness) of the run before it.
  const double angle = 1.234;  // [rad] not a whole number of pinion pitches (20 teeth: 0.314 rad)
  StiffnessEstimator used(rig());
  ASSERT_NE(used.mesh().geometry().phase(angle), used.mesh().geometry().phase(0.0))
      << "the test needs a phase that moves";
  used.setTorque(0.08, angle);
  used.setPreloads(preloads(1500.0));
  used.reset();
  StiffnessEstimator fresh(rig());
  expectSame(used.current(), fresh.current());

  // The same inputs from here on give the same estimates, the preload first (no torque yet).
  expectSame(used.setPreloads(preloads(1200.0)), fresh.setPreloads(preloads(1200.0)));
  EXPECT_EQ(used.current().mesh.phase, fresh.mesh().geometry().phase(0.0));
  expectSame(used.setTorque(-0.05, 0.7), fresh.setTorque(-0.05, 0.7));
  expectSame(used.setPreloads(preloads(900.0)), fresh.setPreloads(preloads(900.0)));
  EXPECT_TRUE(used.shaftRadialStiffness() == fresh.shaftRadialStiffness());
}

// One mean mesh stiffness in the library: the estimator's period mean (both flanks loaded at a
// small torque) is meanMeshStiffness, which the rotor damping and the reduced models take too.
TEST(StiffnessEstimator, MeanMeshStiffnessIsTheLibrarysOne) {
  StiffnessEstimator e(rig());
  const StiffnessEstimate& s = e.setTorque(0.01, 0.3);
  ASSERT_EQ(s.mesh.current.contact, FlankContact::kBoth);
  EXPECT_EQ(s.mesh.mean, meanMeshStiffness(e.mesh()));
  EXPECT_EQ(s.mesh.mean, e.mesh().periodMeans().k1 + e.mesh().periodMeans().k_chain);
}

// Frequency sweeps: in the linear case the RMS peaks fall on the modal frequencies within the step.
#include <gtest/gtest.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/scenes.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"

using namespace drivetrain_stiffness;

TEST(FrequencySweep, LinearPeaksMatchModalFrequencies) {
  const RigConfig rig = loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  SweepSpec spec;
  spec.start = 6000.0;
  spec.stop = 11000.0;
  spec.step = 100.0;
  spec.fidelity = Fidelity::kLinearModal;  // LTI at the mean mesh stiffness: modes are exact there
  spec.include_te = false;
  spec.settle = 0.01;
  spec.measure = 0.005;
  const SweepOutput sweep = torqueSweep(rig, spec);
  // The modes of the same linear model (bearing model at the mean torque, mean mesh stiffness).
  StiffnessEstimator estimator(rig);
  const StiffnessEstimate& e = estimator.setTorque(rig.dynamics.torque);
  std::array<double, 2> kb{{0.0, 0.0}};
  for (std::size_t i = 0; i < e.supports.size(); ++i) kb[rig.bearings[i].shaft] += e.supports[i].solution.radialStiffness();
  const auto modes = modalAnalysis(rigRotorParameters(rig, estimator.mesh(), kb), meanMeshStiffness(estimator.mesh()));
  for (int m : {0, 1}) {  // the two transverse modes inside the sweep
    const double f = modes[m].damped_frequency;
    bool found = false;
    for (const auto& coordinate : sweep.peaks)
      for (const SpectralPeak& p : coordinate) found |= std::abs(p.frequency - f) < spec.step;
    EXPECT_TRUE(found) << "no sweep peak within " << spec.step << " Hz of mode " << m << " at " << f << " Hz";
  }
}

TEST(FrequencySweep, RejectsBadRanges) {
  const RigConfig rig = loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  SweepSpec spec;
  spec.stop = 10.0;  // below start
  EXPECT_THROW(torqueSweep(rig, spec), InvalidInput);
  spec = SweepSpec{};
  spec.step = 0.0;
  EXPECT_THROW(torqueSweep(rig, spec), InvalidInput);
}

// Frequency sweeps: in the linear case the RMS peaks fall on the modal frequencies within the step.
#include <gtest/gtest.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"

using namespace drivetrain_stiffness;

TEST(FrequencySweep, LinearPeaksMatchModalFrequencies) {
  const RigConfig rig =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
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
  for (std::size_t i = 0; i < e.supports.size(); ++i)
    kb[rig.bearings[i].shaft] += e.supports[i].solution.radialStiffness();
  const auto modes = modalAnalysis(rigRotorParameters(rig, estimator.mesh(), kb),
                                   meanMeshStiffness(estimator.mesh()));
  for (int m : {0, 1}) {  // the two transverse modes inside the sweep
    const double f = modes[m].damped_frequency;
    bool found = false;
    for (const auto& coordinate : sweep.peaks)
      for (const SpectralPeak& p : coordinate) found |= std::abs(p.frequency - f) < spec.step;
    EXPECT_TRUE(found) << "no sweep peak within " << spec.step << " Hz of mode " << m << " at " << f
                       << " Hz";
  }
}

// A linear system has one steady state, so stepping up and stepping down must give the same RMS
// at every frequency (the sweep carries the state over, so a window that is not whole periods or
// unsettled transients would show here). The nonlinear anti-backlash model keeps both flanks in
// contact at this amplitude, so it has no jump either.
TEST(FrequencySweep, UpAndDownAgreeWithoutJumps) {
  const RigConfig rig =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  for (Fidelity fidelity : {Fidelity::kLinearModal, Fidelity::kFull}) {
    SweepSpec spec;
    spec.start = 300.0;
    spec.stop = 3000.0;
    spec.step = 300.0;
    spec.fidelity = fidelity;
    spec.direction = SweepDirection::kBoth;
    const SweepOutput sweep = torqueSweep(rig, spec);
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(sweep.rms_down[c].size(), sweep.rms[c].size());
      for (std::size_t i = 0; i < sweep.rms[c].size(); ++i)
        EXPECT_NEAR(sweep.rms_down[c][i] / sweep.rms[c][i], 1.0, 0.01)
            << toString(fidelity) << " coordinate " << c << " at " << sweep.frequency[i] << " Hz";
    }
  }
}

// The spectrum of the whole record of x carries the manufacturing TE at the mesh frequency
// f_mesh = z_p n / 60 = 20 * 1000 / 60 = 333.33 Hz (seed 000 Table 1: z_p = 20, 1000 rpm) as its
// strongest line, within one bin.
TEST(FrequencySweep, RecordSpectrumShowsMeshFrequency) {
  const RigConfig rig =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  SweepSpec spec;
  spec.start = 600.0;
  spec.stop = 1200.0;
  spec.step = 300.0;
  spec.fidelity = Fidelity::kLinearModal;
  const SweepOutput sweep = torqueSweep(rig, spec);
  ASSERT_FALSE(sweep.spectrum_peaks[2].empty());
  EXPECT_NEAR(sweep.spectrum_peaks[2][0].frequency, 20.0 * 1000.0 / 60.0,
              sweep.spectrum_resolution);
}

// A stepped sweep must not kick the system at each step: retuning keeps the torque and its sign of
// slope continuous at the switch time, also late in a long record (large 2 pi f t).
TEST(FrequencySweep, RetuneKeepsTorqueContinuous) {
  TorqueProfile torque;
  torque.kind = TorqueProfile::Kind::kSine;
  torque.mean = 0.1;
  torque.amplitude = 0.05;
  torque.frequency = 60.0;
  for (double t : {0.0137, 1.2345, 4.321}) {
    for (double f_new : {120.0, 2940.0, 61.0}) {
      TorqueProfile next = torque;
      next.retune(f_new, t);
      EXPECT_NEAR(next.at(t), torque.at(t), 1e-12) << t << " " << f_new;
      EXPECT_EQ(next.frequency, f_new);
      const double h = 1e-7;  // the new sine continues in the same direction
      EXPECT_GT((next.at(t + h) - next.at(t)) * (torque.at(t) - torque.at(t - h)), 0.0)
          << t << " " << f_new;
    }
  }
}

TEST(FrequencySweep, RejectsBadRanges) {
  const RigConfig rig =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  SweepSpec spec;
  spec.stop = 10.0;  // below start
  EXPECT_THROW(torqueSweep(rig, spec), InvalidInput);
  spec = SweepSpec{};
  spec.step = 0.0;
  EXPECT_THROW(torqueSweep(rig, spec), InvalidInput);
}

// --direction reads the enum's one name table (core/enum_names.hpp): names round-trip, and a
// refusal names the field, the text and every accepted name.
TEST(FrequencySweep, DirectionNamesRoundTrip) {
  for (const SweepDirection d :
       {SweepDirection::kUp, SweepDirection::kDown, SweepDirection::kBoth}) {
    EXPECT_EQ(parseSweepDirection("--direction", toString(d)), d);
  }
  EXPECT_STREQ(toString(SweepDirection::kBoth), "both");
  try {
    parseSweepDirection("--direction", "sideways");
    ADD_FAILURE() << "accepted 'sideways'";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "--direction = 'sideways': must be 'up', 'down' or 'both'");
  }
}

// The stepped grid: start + i step for i = 0 .. floor((stop - start) / step + 1e-9), each point
// from its index (0.5 + 14 * 0.05 is 1.2 to the last bit, where adding 0.05 fourteen times is not).
TEST(FrequencySweep, GridPointsComeFromTheirIndex) {
  const std::vector<double> g = frequencyGrid("f", 0.5, 1.2, 0.05);
  ASSERT_EQ(g.size(), 15u);  // (1.2 - 0.5) / 0.05 = 14 steps, end included within 1e-9
  for (std::size_t i = 0; i < g.size(); ++i) EXPECT_EQ(g[i], 0.5 + static_cast<double>(i) * 0.05);
  const std::vector<double> hz = frequencyGrid("f", 6000, 11000, 250);
  ASSERT_EQ(hz.size(), 21u);
  EXPECT_EQ(hz.back(), 11000.0);
  EXPECT_EQ(frequencyGrid("f", 60, 3000, 60).size(),
            50u);  // seed 000 section 4.2: 60 Hz to 3 kHz in 60 Hz steps
  EXPECT_EQ(frequencyGrid("f", 1, 1.9, 0.5).size(), 2u);  // stop between points: not reached
  EXPECT_THROW(frequencyGrid("f", 1, 2, 0.0), InvalidInput);
  EXPECT_THROW(frequencyGrid("f", 2, 1, 0.1), InvalidInput);
}

// Up against down: max |a - b| / max(a, b) over the points with a positive maximum, by hand:
// |2 - 1| / 2 = 0.5 beats |4 - 5| / 5 = 0.2; the (0, 0) point is skipped.
TEST(FrequencySweep, LargestRelativeDifferenceByHand) {
  EXPECT_DOUBLE_EQ(largestRelativeDifference({1, 2, 0, 4}, {1, 1, 0, 5}), 0.5);
  EXPECT_DOUBLE_EQ(largestRelativeDifference({3, 0}, {3, 0}), 0.0);
  EXPECT_DOUBLE_EQ(largestRelativeDifference({0}, {7}), 1.0);  // a branch with no response at all
  EXPECT_THROW(largestRelativeDifference({1, 2}, {1}), InvalidInput);
  EXPECT_THROW(largestRelativeDifference({NAN}, {1}), InvalidInput);
}

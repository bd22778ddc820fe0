// The calibration from identified natural frequencies (docs/calibration.md "Natural frequencies"):
// the bearing scales recovered from the frequencies of a rig with known scales, computed as
// drivetrain_rig_sim computes the modes it simulates; the gate; the input checks; and the posterior
// against the linear-Gaussian closed form.
#include <array>
#include <cmath>
#include <iostream>
#include <string>

#include <gtest/gtest.h>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

RigConfig seedRig() {
  RigConfig rig = test::seedServo();
  rig.calibration.present = true;
  rig.calibration.preload_torque = {rig.anti_backlash.preload_torque,
                                    0.2 * rig.anti_backlash.preload_torque};
  return rig;
}

/// The modes of the rig with its mesh scale, bearing scales and preload torque set to `truth`
/// (CalibrationIndex order) at pinion torque [N·m], as drivetrain_rig_sim computes the modes its
/// accelerometers see (rig_vibration.cpp): a StiffnessEstimator of that rig, its shafts' radial
/// stiffness, the period mean of its mesh table. Nothing of the calibrator's.
std::array<Mode, 3> trueModes(const RigConfig& rig, const CalibrationVector& truth, double torque) {
  RigConfig r = rig;
  r.mesh_stiffness_scale = truth[kMeshScale];
  r.anti_backlash.preload_torque = truth[kPreloadTorque];
  for (BearingSupportConfig& b : r.bearings)
    b.stiffness_scale *= b.shaft == 0 ? truth[kPinionBearingScale] : truth[kGearBearingScale];
  StiffnessEstimator estimator(r);
  estimator.setTorque(torque);
  return modalAnalysis(rigRotorParameters(r, estimator.mesh(), estimator.shaftRadialStiffness()),
                       meanMeshStiffness(estimator.mesh()));
}

CalibrationVector nominal(const RigConfig& rig) {
  CalibrationVector p;
  p << 1.0, 1.0, 1.0, rig.anti_backlash.preload_torque, 0.0;
  return p;
}

/// The index of the calibrator's current mode dominated by the same coordinate as `mode`: the
/// matching a pipeline does by mode shape (matchModes), here on the dominant coordinate.
int matched(const Calibrator& calibrator, const Mode& mode, double torque,
            const StiffnessEstimator& supports) {
  const std::array<Mode, 3> model = calibrator.modes(torque, supports);
  for (int k = 0; k < 3; ++k)
    if (model[k].dominant == mode.dominant) return k;
  return -1;
}

constexpr double kTorque = 2.0;  // [N·m] below the seed's knee (6.95 N·m): both flanks in mesh

TEST(CalibratorModes, NaturalFrequenciesAloneIdentifyBothBearingScales) {
  // A rig whose pinion bearings are 0.8 and gear bearings 1.2 times the drawing's: at 2 N·m its
  // transverse modes cross (the pinion's falls from 8.34 to 7.43 kHz, below the gear's, which rises
  // from 7.02 to 7.72 kHz). Four records of both frequencies at one constant torque, 0.05 % std, no
  // encoder reading at all (no baseline): both scales within 1 %, identified; the mesh scale and
  // T_p, which the transverse modes barely see, keep nearly their prior std.
  const RigConfig rig = seedRig();
  CalibrationVector truth = nominal(rig);
  truth[kPinionBearingScale] = 0.8;
  truth[kGearBearingScale] = 1.2;
  const std::array<Mode, 3> measured = trueModes(rig, truth, kTorque);
  StiffnessEstimator supports(rig);
  supports.setTorque(kTorque);
  Calibrator calibrator(rig);
  const CalibrationBands prior = calibrator.bands(kTorque, supports, true);
  EXPECT_FALSE(prior.calibrated);
  for (int record = 0; record < 4; ++record) {
    std::array<ModalFrequency, 2> f{};
    for (int k = 0; k < 2; ++k) {  // the two transverse modes
      f[k].mode = matched(calibrator, measured[k], kTorque, supports);
      ASSERT_GE(f[k].mode, 0) << measured[k].dominant;
      f[k].frequency = measured[k].natural_frequency;
      f[k].frequency_std = 5e-4 * measured[k].natural_frequency;
    }
    EXPECT_EQ(calibrator.modalUpdate(1.0 + record, f.data(), f.size(), kTorque, supports),
              WindowOutcome::kUpdated)
        << "record " << record << ", NIS " << calibrator.estimate().modal_nis;
  }
  const CalibrationEstimate& e = calibrator.estimate();
  std::cout << "true modes " << measured[0].natural_frequency << " Hz " << measured[0].dominant
            << ", " << measured[1].natural_frequency << " Hz " << measured[1].dominant
            << "\nestimate " << e.value.transpose() << "\nstd      " << e.std.transpose()
            << "\nmodal NIS " << e.modal_nis << "\n";
  EXPECT_EQ(e.modal_updates, 4u);
  EXPECT_EQ(e.updates, 0u);
  EXPECT_NEAR(e.value[kPinionBearingScale] / 0.8, 1.0, 0.01);
  EXPECT_NEAR(e.value[kGearBearingScale] / 1.2, 1.0, 0.01);
  EXPECT_TRUE(e.identified[kPinionBearingScale]);
  EXPECT_TRUE(e.identified[kGearBearingScale]);
  EXPECT_FALSE(e.identified[kMeshScale]);
  EXPECT_FALSE(e.identified[kPreloadTorque]);
  EXPECT_GT(e.std[kMeshScale], 0.9 * e.prior_std[kMeshScale]);
  EXPECT_GT(e.std[kPreloadTorque], 0.9 * e.prior_std[kPreloadTorque]);
  // The modes do not read the TE offset: its std only takes the random walk over the 3 s.
  EXPECT_GE(e.std[kTeOffset], e.prior_std[kTeOffset]);
  EXPECT_NEAR(e.std[kTeOffset] / e.prior_std[kTeOffset], 1.0, 1e-6);
  // The bands narrow: the bearing stiffness to a tenth, the transverse modes' frequencies too.
  const CalibrationBands after = calibrator.bands(kTorque, supports, true);
  EXPECT_TRUE(after.calibrated);
  for (int s = 0; s < 2; ++s) {
    EXPECT_LT(after.bearing_stiffness_high[s] - after.bearing_stiffness_low[s],
              0.1 * (prior.bearing_stiffness_high[s] - prior.bearing_stiffness_low[s]))
        << "shaft " << s;
  }
  for (int k = 0; k < 2; ++k) {
    EXPECT_LT(after.natural_frequency_high[k] - after.natural_frequency_low[k],
              0.1 * (prior.natural_frequency_high[k] - prior.natural_frequency_low[k]))
        << "mode " << k;
    EXPECT_NEAR(after.natural_frequency[k] / measured[k].natural_frequency, 1.0, 1e-3);
  }
  // modes() is bands()'s modal analysis, bit for bit.
  const std::array<Mode, 3> modes = calibrator.modes(kTorque, supports);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(modes[k].natural_frequency, after.natural_frequency[k]);
  // The encoders' windows still wait, and the sentence says what did update.
  EXPECT_EQ(calibrator.waitingReason().rfind(
                "4 records of natural frequencies updated the calibration, the encoders' TE not "
                "yet: no encoder reading",
                0),
            0u)
      << calibrator.waitingReason();
}

TEST(CalibratorModes, AFrequencyThirtyStdOffIsGated) {
  // After two records, a record of the gear mode 30 innovation std off its prediction: NIS ~900,
  // far over chi^2(1 dof, 0.999) = 10.83. Gated, counted, the estimate unchanged bit for bit; one
  // 1 std off updates.
  const RigConfig rig = seedRig();
  StiffnessEstimator supports(rig);
  supports.setTorque(kTorque);
  Calibrator calibrator(rig);
  const std::array<Mode, 3> measured = trueModes(rig, nominal(rig), kTorque);
  for (int record = 0; record < 2; ++record) {
    const std::array<ModalFrequency, 2> f{
        {{0, measured[0].natural_frequency, 5.0}, {1, measured[1].natural_frequency, 5.0}}};
    ASSERT_EQ(calibrator.modalUpdate(record, f.data(), 2, kTorque, supports),
              WindowOutcome::kUpdated);
  }
  const CalibrationEstimate before = calibrator.estimate();
  const CalibrationMatrix covariance = calibrator.covariance();
  // The innovation's std: the prediction's (the band's half-width over 1.96), the record's own and
  // the model error of the third record of this mode (3 x (0.002 f)^2).
  const double f0 = before.natural_frequency[0];
  const double predicted = (before.natural_frequency_high[0] - f0) / 1.959963984540054;
  const double model = rig.calibration.modal_model_error * f0;
  const double innovation_std = std::sqrt(predicted * predicted + 25.0 + 3.0 * model * model);
  const ModalFrequency off{0, f0 + 30.0 * innovation_std, 5.0};
  EXPECT_EQ(calibrator.modalUpdate(3.0, &off, 1, kTorque, supports), WindowOutcome::kGated);
  const CalibrationEstimate& e = calibrator.estimate();
  EXPECT_EQ(e.modal_gated, 1u);
  EXPECT_EQ(e.modal_updates, 2u);
  EXPECT_NEAR(e.modal_nis, 900.0, 90.0);
  EXPECT_EQ(e.value, before.value);
  EXPECT_EQ(e.std, before.std);
  EXPECT_EQ(calibrator.covariance(), covariance);
  const ModalFrequency near{0, f0 + innovation_std, 5.0};
  EXPECT_EQ(calibrator.modalUpdate(4.0, &near, 1, kTorque, supports), WindowOutcome::kUpdated);
  EXPECT_NEAR(calibrator.estimate().modal_nis, 1.0, 0.1);
  EXPECT_EQ(calibrator.estimate().modal_updates, 3u);
}

TEST(CalibratorModes, RefusesBadFrequenciesNamingTheField) {
  const RigConfig rig = seedRig();
  StiffnessEstimator supports(rig);
  Calibrator calibrator(rig);
  auto message = [&](const ModalFrequency& f) {
    try {
      calibrator.modalUpdate(1.0, &f, 1, kTorque, supports);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message({3, 8000.0, 5.0}).find("natural frequencies[0].mode"), std::string::npos);
  EXPECT_NE(message({-1, 8000.0, 5.0}).find("natural frequencies[0].mode"), std::string::npos);
  EXPECT_NE(message({0, std::nan(""), 5.0}).find("natural frequencies[0].frequency"),
            std::string::npos);
  EXPECT_NE(message({0, -8000.0, 5.0}).find("natural frequencies[0].frequency"), std::string::npos);
  EXPECT_NE(message({0, 8000.0, 0.0}).find("natural frequencies[0].frequency_std"),
            std::string::npos);
  EXPECT_NE(message({0, 8000.0, HUGE_VAL}).find("natural frequencies[0].frequency_std"),
            std::string::npos);
  const std::array<ModalFrequency, 2> twice{{{1, 9000.0, 5.0}, {1, 9100.0, 5.0}}};
  EXPECT_THROW(calibrator.modalUpdate(1.0, twice.data(), 2, kTorque, supports), InvalidInput);
  const std::array<ModalFrequency, 4> four{};
  EXPECT_THROW(calibrator.modalUpdate(1.0, four.data(), 4, kTorque, supports), InvalidInput);
  EXPECT_EQ(calibrator.modalUpdate(1.0, nullptr, 0, kTorque, supports), WindowOutcome::kNone);
  const CalibrationEstimate& e = calibrator.estimate();
  EXPECT_EQ(e.modal_updates + e.modal_gated, 0u);
  EXPECT_EQ(e.std, e.prior_std);
  EXPECT_FALSE(calibrator.bands(kTorque, supports, false).calibrated);
}

TEST(CalibratorModes, OneRecordMatchesTheLinearGaussianPosterior) {
  // One record of one frequency, measured where the prior predicts it: the posterior variance is
  // the linear-Gaussian one, P - P g (g' P g + R)^-1 g' P, with g the frequency's sensitivity to
  // the parameters by finite differences of trueModes (not of the calibrator) and
  // R = std^2 + (modal_model_error f)^2. Alone, the gear bearing scale (every other parameter
  // held): 1 / (1 / var_prior + g^2 / R).
  for (const bool alone : {true, false}) {
    RigConfig rig = seedRig();
    if (alone) {
      rig.calibration.mesh_stiffness_scale.std = 0.0;
      rig.calibration.pinion_bearing_scale.std = 0.0;
      rig.calibration.preload_torque.std = 0.0;
      rig.calibration.te_offset.std = 0.0;
    }
    StiffnessEstimator supports(rig);
    supports.setTorque(kTorque);
    Calibrator calibrator(rig);
    const CalibrationVector p0 = nominal(rig);
    const std::array<Mode, 3> modes = trueModes(rig, p0, kTorque);
    const int k = modes[0].dominant == "x_g" ? 0 : 1;  // the gear shaft's mode
    ASSERT_EQ(modes[k].dominant, "x_g");
    const double f = modes[k].natural_frequency, sigma = 1e-3 * f;
    Eigen::Matrix<double, kCalibrationSize, 1> g =
        Eigen::Matrix<double, kCalibrationSize, 1>::Zero();
    const CalibrationVector prior_std = calibrator.estimate().prior_std;
    for (int i : {kMeshScale, kPinionBearingScale, kGearBearingScale, kPreloadTorque}) {
      if (!(prior_std[i] > 0.0)) continue;
      const double h = 1e-4 * std::max(1.0, std::abs(p0[i]));
      CalibrationVector a = p0, b = p0;
      a[i] += h;
      b[i] -= h;
      g[i] = (trueModes(rig, a, kTorque)[k].natural_frequency -
              trueModes(rig, b, kTorque)[k].natural_frequency) /
             (2.0 * h);
    }
    const double model = rig.calibration.modal_model_error * f;
    const double R = sigma * sigma + model * model;
    const CalibrationMatrix P = prior_std.cwiseAbs2().asDiagonal();
    const CalibrationVector Pg = P * g;
    const double expected = P(kGearBearingScale, kGearBearingScale) -
                            Pg[kGearBearingScale] * Pg[kGearBearingScale] / (g.dot(Pg) + R);
    if (alone) {
      const double scalar = 1.0 / (1.0 / P(kGearBearingScale, kGearBearingScale) +
                                   g[kGearBearingScale] * g[kGearBearingScale] / R);
      EXPECT_NEAR(expected / scalar, 1.0, 1e-12);
    }
    const ModalFrequency record{k, f, sigma};
    ASSERT_EQ(calibrator.modalUpdate(1.0, &record, 1, kTorque, supports), WindowOutcome::kUpdated);
    const double std_gear = calibrator.estimate().std[kGearBearingScale];
    std::cout << (alone ? "alone" : "all estimated") << ": g " << g.transpose() << "\n  std "
              << std_gear << ", closed form " << std::sqrt(expected) << "\n";
    EXPECT_NEAR(std_gear / std::sqrt(expected), 1.0, 0.02);
    EXPECT_NEAR(calibrator.estimate().value[kGearBearingScale], 1.0, 1e-6);
  }
}

TEST(CalibratorModes, AVeeringRigDoesNotRunToTheBounds) {
  // A drawn rig of the modal validation (scripts/modal_validation, seed 1, rig 24): bearing scales
  // 0.7636 (pinion) and 1.0799 (gear), mesh scale 0.9522, at 0.1 N·m. Its transverse
  // modes lie 2.2 % apart with mixed shapes: 8,103 Hz (x_p) below 8,285 Hz (x_g), where the
  // drawing has 9,377 Hz (x_p) above 7,884 Hz (x_g). One record of both frequencies with the stds
  // of an 80 s identification (1.71 and 4.73 Hz), no model error. Full Gauss-Newton steps took the
  // scales to 0.95 and 1.36 (7.6 and 19.9, the bound, in the 80 s replay); with steps that lower
  // the posterior's cost the update lands within 0.5 % of the truth (the issue asks 3 %).
  RigConfig rig = seedRig();
  rig.calibration.modal_model_error = 0.0;
  const double torque = 0.1;
  CalibrationVector truth = nominal(rig);
  truth[kMeshScale] = 0.952169707954613;
  truth[kPinionBearingScale] = 0.7635527420243946;
  truth[kGearBearingScale] = 1.0798959676219346;
  const std::array<Mode, 3> measured = trueModes(rig, truth, torque);
  ASSERT_EQ(measured[0].dominant, "x_p");
  ASSERT_EQ(measured[1].dominant, "x_g");
  ASSERT_LT(measured[1].natural_frequency / measured[0].natural_frequency, 1.03);
  StiffnessEstimator supports(rig);
  supports.setTorque(torque);
  Calibrator calibrator(rig);
  std::array<ModalFrequency, 2> f{};
  for (int k = 0; k < 2; ++k) {
    f[k].mode = matched(calibrator, measured[k], torque, supports);
    f[k].frequency = measured[k].natural_frequency;
    f[k].frequency_std = k == 0 ? 1.71 : 4.73;
  }
  ASSERT_EQ(calibrator.modalUpdate(1.0, f.data(), 2, torque, supports), WindowOutcome::kUpdated);
  const CalibrationEstimate& e = calibrator.estimate();
  std::cout << "estimate " << e.value.transpose() << "\n";
  for (int i : {kPinionBearingScale, kGearBearingScale}) {
    EXPECT_NEAR(e.value[i] / truth[i], 1.0, 5e-3) << i;
    EXPECT_TRUE(e.identified[i]) << i;
  }
}

}  // namespace
}  // namespace drivetrain_stiffness

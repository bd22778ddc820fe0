// The live calibration (docs/calibration.md): the static encoder-TE model against independent
// period integrals of the mesh table, the order regression against a synthetic signal, and the
// calibrator against synthetic encoder readings of a rig whose parameters are known.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "seed_rig.hpp"           // NOLINT(build/include_subdir)
#include "static_te_encoder.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

RigConfig seedRig() {
  RigConfig rig = test::seedServo();
  rig.calibration.present = true;
  rig.calibration.preload_torque = {rig.anti_backlash.preload_torque,
                                    0.2 * rig.anti_backlash.preload_torque};
  return rig;
}

CalibrationVector nominal(const RigConfig& rig) {
  CalibrationVector p;
  p << 1.0, 1.0, 1.0, rig.anti_backlash.preload_torque, 0.0;
  return p;
}

/// The period mean of f(k1, k_c) by 20000 midpoints of the mesh table's exact pair sums: an
/// integration independent of StaticTeModel's grid (which splits at the switching phases).
template <typename F>
double periodMean(const AntiBacklashMesh& mesh, F f) {
  const int n = 20000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const CompositeMesh c = mesh.exactAt((i + 0.5) / n, 0.0);
    sum += f(c.k1, c.k_chain);
  }
  return sum / n;
}

/// The seed gearbox without its calibration block and with `extra` appended (the bearing file
/// path made absolute), loaded.
RigConfig seedWith(const std::string& extra, const std::string& bearing_extra = "") {
  const std::string dir = std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/";
  std::ifstream in(dir + "seed_servo.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (std::size_t at = text.find("file: ../"); at != std::string::npos;
       at = text.find("file: ../", at)) {
    text.replace(at, 9, "file: " + dir + "../");
  }
  const std::size_t own = text.find("\ncalibration:");  // the seed's own block gives way to `extra`
  if (own != std::string::npos) text.erase(own + 1);
  if (!bearing_extra.empty()) {
    const std::size_t at = text.find("    mesh_load_share: 1.0");
    text.insert(at, "    " + bearing_extra + "\n");
  }
  const std::string path = ::testing::TempDir() + "calibration_seed.yaml";
  std::ofstream(path) << text << "\n" << extra << "\n";
  return loadRigFile(path);
}

TEST(CalibrationConfig, PriorsDefaultToTheRigsOwnValues) {
  const RigConfig rig =
      seedWith("calibration:\n  te_offset: {std: 2.0e-6}", "stiffness_scale: 1.3");
  ASSERT_TRUE(rig.calibration.present);
  EXPECT_DOUBLE_EQ(rig.calibration.preload_torque.mean, rig.anti_backlash.preload_torque);
  EXPECT_DOUBLE_EQ(rig.calibration.preload_torque.std, 0.2 * rig.anti_backlash.preload_torque);
  EXPECT_DOUBLE_EQ(rig.calibration.pinion_bearing_scale.mean,
                   1.3);  // the pinion support's stiffness_scale
  EXPECT_DOUBLE_EQ(rig.calibration.gear_bearing_scale.mean, 1.0);
  EXPECT_DOUBLE_EQ(rig.calibration.te_offset.std, 2e-6);
  EXPECT_EQ(rig.calibration.modal_model_error, 0.002);  // docs/calibration.md "Natural frequencies"
  EXPECT_DOUBLE_EQ(rig.bearings[0].stiffness_scale, 1.3);
}

TEST(CalibrationConfig, RefusesBadValuesNamingTheField) {
  auto message = [](const std::string& extra) {
    try {
      seedWith(extra);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("calibration:\n  mesh_stiffness_scale: {mean: 1.0, std: -0.1}")
                .find("calibration.mesh_stiffness_scale.std"),
            std::string::npos);
  EXPECT_NE(message("calibration:\n  preload_torque: {mean: .nan}")
                .find("calibration.preload_torque.mean"),
            std::string::npos);
  EXPECT_NE(message("calibration:\n  gate: 0").find("calibration.gate"), std::string::npos);
  EXPECT_NE(
      message("calibration:\n  modal_model_error: -0.001").find("calibration.modal_model_error"),
      std::string::npos);
  EXPECT_NE(
      message("calibration:\n  modal_model_error: .nan").find("calibration.modal_model_error"),
      std::string::npos);
  EXPECT_EQ(seedWith("calibration:\n  modal_model_error: 0.005").calibration.modal_model_error,
            0.005);
  EXPECT_NE(message("calibration:\n  typo: 1").find("calibration.typo: unknown key"),
            std::string::npos);
  EXPECT_NE(
      message("calibration:\n  te_offset: 3").find("calibration.te_offset: must be a mapping"),
      std::string::npos);
  EXPECT_NE(
      message("calibration:\n  mesh_stiffness_scale: {mean: 1.0, std: 0.01, reference_std: -0.2}")
          .find("calibration.mesh_stiffness_scale.reference_std"),
      std::string::npos);
  EXPECT_NE(
      message("calibration:\n  mesh_stiffness_scale: {mean: 1.0, std: 0.01, reference_std: .inf}")
          .find("calibration.mesh_stiffness_scale.reference_std"),
      std::string::npos);
  // Zero for an estimated parameter: refused (it could never be identified nor drift).
  EXPECT_NE(
      message("calibration:\n  mesh_stiffness_scale: {mean: 1.0, std: 0.01, reference_std: 0.0}")
          .find("calibration.mesh_stiffness_scale.reference_std"),
      std::string::npos);
  EXPECT_EQ(
      message("calibration:\n  mesh_stiffness_scale: {mean: 1.0, std: 0.0, reference_std: 0.0}"),
      "accepted");
  // Given, it is kept; absent, the prior's std is the reference.
  const RigConfig kept =
      seedWith("calibration:\n  mesh_stiffness_scale: {mean: 0.9, std: 0.01, reference_std: 0.2}");
  EXPECT_EQ(kept.calibration.mesh_stiffness_scale.reference(), 0.2);
  EXPECT_EQ(kept.calibration.gear_bearing_scale.reference(),
            kept.calibration.gear_bearing_scale.std);
}

TEST(StaticTeModel, MeanTeMatchesTheFlankStateClosedForms) {
  const RigConfig rig = seedRig();
  StaticTeModel model(rig);
  const AntiBacklashMesh mesh(rig);
  const CalibrationVector p = nominal(rig);
  const std::array<double, 2> none{0.0, 0.0};
  const double fp = rig.anti_backlash.preload_torque / model.baseRadius()[1];
  // Both flanks (0.5 N·m is far below the knee, ~7 N·m): delta = F / (k1 + k_c) (seed 000 eq 1).
  const double t_low = 0.5, f_low = t_low / model.baseRadius()[0];
  const double both = periodMean(mesh, [&](double k1, double kc) { return f_low / (k1 + kc); });
  EXPECT_NEAR(model.features(p, t_low, none, 0.0, none)[0] / both, 1.0, 2e-4);
  // Drive flank only (20 N·m, beyond every phase's knee): delta = (F - F_p) / k1.
  const double t_high = 20.0, f_high = t_high / model.baseRadius()[0];
  const double drive = periodMean(mesh, [&](double k1, double) { return (f_high - fp) / k1; });
  EXPECT_NEAR(model.features(p, t_high, none, 0.0, none)[0] / drive, 1.0, 2e-4);
  // Back flank only (-5 N·m): delta = (F + F_p) / k_c, the soft scissor spring.
  const double t_back = -5.0, f_back = t_back / model.baseRadius()[0];
  const double back = periodMean(mesh, [&](double, double kc) { return (f_back + fp) / kc; });
  EXPECT_NEAR(model.features(p, t_back, none, 0.0, none)[0] / back, 1.0, 2e-4);
  // A mesh scale s divides the tooth compliance (k_c only partly: the spring is not scaled).
  CalibrationVector stiffer = p;
  stiffer[kMeshScale] = 1.25;
  EXPECT_NEAR(model.features(stiffer, t_high, none, 0.0, none)[0] / drive, 1.0 / 1.25, 2e-4);
}

// One mesh table per rig: the model reads the rig's own table (the stiffness estimator's) when it
// is the drawing's (mesh.stiffness_scale 1), and builds one at scale 1 otherwise, whose tooth
// stiffness is the scaled table's divided by the scale (AntiBacklashMesh multiplies k1 and k2).
TEST(StaticTeModel, SharesTheRigsTableOnlyAtTheDrawingsScale) {
  const RigConfig rig = seedRig();
  ASSERT_EQ(rig.mesh_stiffness_scale, 1.0);
  const auto table = std::make_shared<const AntiBacklashMesh>(rig);
  const StaticTeModel shared(rig, table);
  EXPECT_EQ(&shared.unitMesh(), table.get());
  // Features identical to a model with its own table: the same constructor arguments.
  const StaticTeModel own(rig);
  EXPECT_NE(&own.unitMesh(), table.get());
  const CalibrationVector p = nominal(rig);
  const std::array<double, 2> none{0.0, 0.0};
  EXPECT_TRUE(shared.features(p, 3.0, none, 0.0, none) == own.features(p, 3.0, none, 0.0, none));

  RigConfig softer = rig;
  softer.mesh_stiffness_scale = 0.8;
  const auto scaled = std::make_shared<const AntiBacklashMesh>(softer);
  const StaticTeModel unit(softer, scaled);
  EXPECT_NE(&unit.unitMesh(), scaled.get());
  EXPECT_EQ(unit.unitMesh().stiffnessScale(), 1.0);
  for (const double phase : {0.1, 0.45, 0.8}) {
    const CompositeMesh a = unit.unitMesh().at(phase, 0.0), b = scaled->at(phase, 0.0);
    EXPECT_NEAR(a.k1, b.k1 / 0.8, 1e-9 * a.k1) << phase;
    EXPECT_NEAR(a.k2, b.k2 / 0.8, 1e-9 * a.k2) << phase;
  }
}

TEST(StaticTeModel, KneeIsWhereTheBackHalfLifts) {
  const RigConfig rig = seedRig();
  StaticTeModel model(rig);
  const CalibrationVector p = nominal(rig);
  const double knee = model.kneeTorque(p);
  // F_p (1 + k1/k_c) with the seed's numbers: F_p = 1 N·m / r_b,g = 88.7 N and k1/k_c ~ 11
  // (k_te = 1e7 N/m in series with k2 ~ 1e8 N/m), so ~1000 N of mesh force, ~6-7 N·m of pinion
  // torque.
  EXPECT_GT(knee, 5.0);
  EXPECT_LT(knee, 8.0);
  // The mean mesh stiffness drops from k1 + k_c to k1 across the knee (phase by phase).
  EXPECT_GT(model.meanMeshStiffness(p, 0.5 * knee), model.meanMeshStiffness(p, 2.0 * knee) * 1.05);
  // The knee scales with T_p.
  CalibrationVector q = p;
  q[kPreloadTorque] *= 1.2;
  EXPECT_NEAR(model.kneeTorque(q) / knee, 1.2, 1e-12);
}

// The period-mean mesh stiffness is asked for at every stiffness message; where both flanks are
// loaded at every phase it does not depend on the force, and the model keeps it per parameter
// vector. That must be invisible: each value equals, bit for bit, the one a fresh model gives, in
// every flank state and across the knee (where the force range of the kept value ends), whatever
// was asked before; and below the knee it equals the both-flank period mean of the mesh table, an
// independent integral (periodMean above).
TEST(StaticTeModel, KeptBothFlankMeanIsInvisible) {
  const RigConfig rig = seedRig();
  const StaticTeModel warm(rig);
  const CalibrationVector p = nominal(rig);
  CalibrationVector q = p;
  q[kMeshScale] = 0.9;
  q[kPreloadTorque] *= 1.1;
  const double knee = warm.kneeTorque(p);
  for (int pass = 0; pass < 2; ++pass) {
    for (double torque :
         {0.1, -0.3, 0.5 * knee, 0.999 * knee, 1.001 * knee, 2.0 * knee, -5.0, 0.0}) {
      for (const CalibrationVector& v : {p, q}) {
        const StaticTeModel fresh(rig);
        EXPECT_EQ(warm.meanMeshStiffness(v, torque), fresh.meanMeshStiffness(v, torque))
            << torque << " pass " << pass;
      }
    }
  }
  const AntiBacklashMesh mesh(rig.gears, rig.anti_backlash, rig.mesh_model, rig.mesh_samples, 1.0);
  const double both = periodMean(mesh, [](double k1, double kc) { return k1 + kc; });
  EXPECT_NEAR(warm.meanMeshStiffness(p, 0.1) / both, 1.0, 2e-4);
  // Outside the both-flank range the flank states come from the kept k1, k_c per grid point; far
  // above the knee every phase has the back half lifted (the mean is k1's), far past the reverse
  // knee every phase runs through the spring chain alone (k_c's): the independent integrals again.
  // (Reverse knee: -F_p (1 + k_c/k1) ~ -97 N of mesh force, ~ -1.3 N·m; -20 N·m is far past it.)
  const double drive = periodMean(mesh, [](double k1, double) { return k1; });
  const double back = periodMean(mesh, [](double, double kc) { return kc; });
  EXPECT_NEAR(warm.meanMeshStiffness(p, 3.0 * knee) / drive, 1.0, 2e-4);
  EXPECT_NEAR(warm.meanMeshStiffness(p, -20.0) / back, 1.0, 2e-4);
}

// Above and near the knees the period mean depends on the force only through the grid points'
// flank states; the model keeps the last sum with the range of forces in which none of them
// changes state. That must be invisible too: a fine sweep through both knee regions, up, down and
// jumping, gives bit for bit what a fresh model gives at every torque, and it does cross many
// changes of the states (distinct sums).
TEST(StaticTeModel, HeldFlankSumIsInvisible) {
  const RigConfig rig = seedRig();
  const StaticTeModel warm(rig);
  const CalibrationVector p = nominal(rig);
  const double knee = warm.kneeTorque(p);
  std::vector<double> torques;
  for (int i = 0; i <= 300; ++i)
    torques.push_back(knee * (0.6 + 1.0 * i / 300.0));  // up through the knee
  for (int i = 300; i >= 0; --i) torques.push_back(knee * (0.6 + 1.0 * i / 300.0));  // and down
  for (int i = 0; i <= 200; ++i)
    torques.push_back(-0.2 - 1.0 * i / 200.0);  // the reverse knee, -0.55 N m
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> any(-1.5, 1.6 * knee);
  for (int i = 0; i < 200; ++i) torques.push_back(any(rng));
  std::set<double> sums;
  for (double torque : torques) {
    const StaticTeModel fresh(rig);
    const double k = warm.meanMeshStiffness(p, torque);
    ASSERT_EQ(k, fresh.meanMeshStiffness(p, torque)) << torque << " N m";
    sums.insert(k);
  }
  EXPECT_GT(sums.size(), 20u) << "the sweep should cross many points' changes of state";
}

// The held range comes from the divided bounds F_p (1 + k1/k_c), while flankContact decides by the
// multiplied-out products: within a few ulps of a bound the two disagree. A force there, still
// both-flank by the products but past the divided bound, must not leave a range that covers the
// forces just above it, where that point carries the drive flank alone (found by an independent
// review: 5.0e-4 of the mean off at these two torques, mesh scale 0.8 and T_p 0.7 of the
// drawing's); nor may a NaN force leave a range at all.
TEST(StaticTeModel, HeldFlankSumNearABoundsRounding) {
  const RigConfig rig = seedRig();
  CalibrationVector p = nominal(rig);
  p[kMeshScale] = 0.8;
  p[kPreloadTorque] *= 0.7;
  const StaticTeModel warm(rig);
  for (double torque : {2.818598152387636, 2.8185981523960915}) {
    const StaticTeModel fresh(rig);
    EXPECT_EQ(warm.meanMeshStiffness(p, torque), fresh.meanMeshStiffness(p, torque))
        << torque << " N m";
  }
  const StaticTeModel after_nan(rig);
  after_nan.meanMeshStiffness(p, std::numeric_limits<double>::quiet_NaN());
  const double knee = after_nan.kneeTorque(p);
  const StaticTeModel fresh(rig);
  EXPECT_EQ(after_nan.meanMeshStiffness(p, 3.0 * knee), fresh.meanMeshStiffness(p, 3.0 * knee));
}

TEST(StaticTeModel, BearingDeflectionIsTheSecantNotTheTangent) {
  RigConfig rig = seedRig();
  StaticTeModel model(rig);
  StiffnessEstimator estimator(rig);
  std::array<double, 2> d{};
  model.shaftDeflection(4.0, estimator, d);
  // Independent: the support's own solve at the two loads (bearing_support.hpp).
  const BearingSupportConfig& c = rig.bearings[0];
  const BearingSupport support(c.spec, c.arrangement, c.axial_preload, c.interference, c.tilt);
  Vector5d load = Vector5d::Zero();
  load[kUx] = c.radial_preload;
  const double u0 = support.solve(load).displacement[kUx];
  load[kUx] = c.radial_preload + 4.0 / model.baseRadius()[0];
  const double u1 = support.solve(load).displacement[kUx];
  EXPECT_NEAR(d[0], u1 - u0, 1e-12);
  // Reversed torque: the same magnitude, the other way along the line of action.
  std::array<double, 2> r{};
  model.shaftDeflection(-4.0, estimator, r);
  EXPECT_NEAR(r[0], -d[0], 1e-15);
  // The secant compliance exceeds the tangent's F / k_xx: the axial spring preload lets the shaft
  // float axially, which k_xx (axial displacement held) does not (docs/calibration.md).
  estimator.setTorque(4.0);
  EXPECT_GT(d[0], 1.2 * (4.0 / model.baseRadius()[0]) / estimator.shaftRadialStiffness()[0]);
}

// shaftDeflection keeps its last result and the unloaded solutions (the calibrator asks at every
// encoder reading, five per torque message). A new preload, a reset, or another estimator must
// never get a kept value: each answer equals a fresh model's, bit for bit.
TEST(StaticTeModel, KeptShaftDeflectionFollowsThePreloads) {
  const RigConfig rig = seedRig();
  StaticTeModel warm(rig);
  StiffnessEstimator a(rig), b(rig);
  const BearingSupportConfig& c = rig.bearings[0];
  b.setPreloads({{c.name, 0.5 * c.axial_preload, c.radial_preload, c.interference.inner,
                  c.interference.outer}});
  auto fresh = [&](double torque, const StiffnessEstimator& e) {
    StaticTeModel model(rig);
    std::array<double, 2> d{};
    model.shaftDeflection(torque, e, d);
    return d;
  };
  std::array<double, 2> d{};
  warm.shaftDeflection(4.0, a, d);
  const std::array<double, 2> a4 = fresh(4.0, a);
  EXPECT_EQ(d, a4);
  warm.shaftDeflection(4.0, a, d);  // the same question: the kept answer
  EXPECT_EQ(d, a4);
  warm.shaftDeflection(4.0, b, d);  // another estimator, the same torque: a half axial preload
  EXPECT_EQ(d, fresh(4.0, b));
  EXPECT_GT(std::abs(d[0]), 1.05 * std::abs(a4[0]));  // a softer support: the cache was not used
  warm.shaftDeflection(-2.0, b, d);
  EXPECT_EQ(d, fresh(-2.0, b));
  // A preload change on the same estimator, at the torque asked last.
  b.setPreloads({{c.name, c.axial_preload, c.radial_preload + 50.0, c.interference.inner,
                  c.interference.outer}});
  warm.shaftDeflection(-2.0, b, d);
  EXPECT_EQ(d, fresh(-2.0, b));
  b.reset();
  warm.shaftDeflection(-2.0, b, d);
  EXPECT_EQ(d, fresh(-2.0, b));
  EXPECT_NE(a.supportsRevision(), b.supportsRevision());
}

TEST(OrderRegression, SeparatesMeshHarmonicsFromShaftOrders) {
  OrderRegression reg(20, 40);
  EXPECT_EQ(reg.orderCount(), 3);  // 1, 2 and 0.5 pinion orders (the gear's 2x is the pinion's 1x)
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> noise(-1e-8, 1e-8);
  const double c1 = 1e-6, c2 = 0.3e-6;
  for (int i = 0; i < 20000; ++i) {
    const double theta = 4.0 * kTwoPi * i / 20000.0 + 0.1;  // two gear turns
    const double phase = 20.0 * theta / kTwoPi + 0.25;
    const double x = 5e-3 + c1 * std::cos(kTwoPi * phase - 0.4) +
                     c2 * std::sin(2.0 * kTwoPi * phase) + 0.5e-6 * std::sin(theta + 0.3) +
                     0.2e-6 * std::cos(0.5 * theta) + 0.1e-6 * std::cos(2.0 * theta) + noise(rng);
    reg.add(theta, phase - std::floor(phase), x);
  }
  OrderRegression::Fit fit;
  ASSERT_TRUE(reg.solve(fit));
  EXPECT_NEAR(fit.mean, 5e-3, 1e-9);
  EXPECT_NEAR(std::abs(fit.harmonics[0]), c1, 1e-9);
  EXPECT_NEAR(std::arg(fit.harmonics[0]), -0.4,
              1e-3);  // a cos(. - 0.4) = Re(a e^{-0.4i} e^{i .}): C = a e^{-0.4i}
  EXPECT_NEAR(std::abs(fit.harmonics[1]), c2, 1e-9);
  EXPECT_NEAR(reg.orders(fit, 1.0),
              0.5e-6 * std::sin(1.3) + 0.2e-6 * std::cos(0.5) + 0.1e-6 * std::cos(2.0), 1e-9);
  // The noise is uniform in +-1e-8 m: rms 1e-8 / sqrt(3).
  EXPECT_NEAR(fit.residual_rms, 1e-8 / std::sqrt(3.0), 1e-10);
  EXPECT_NEAR(fit.mean_std / (1e-8 / std::sqrt(3.0) / std::sqrt(20000.0)), 1.0,
              0.05);  // sigma / sqrt(n), orthogonal basis
}

TEST(OrderRegression, RefusesAnUnderdeterminedWindow) {
  OrderRegression reg(20, 40);
  // Fewer than four readings per term: no fit (the window's noise could not be estimated).
  for (int i = 0; i < 4 * reg.terms() - 1; ++i)
    reg.add(0.01 * i, 0.2 * i - std::floor(0.2 * i), 1e-6);
  OrderRegression::Fit fit;
  EXPECT_FALSE(reg.solve(fit));
  // All readings at one angle: the shaft orders and the mean cannot be told apart.
  OrderRegression still(20, 40);
  for (int i = 0; i < 1000; ++i) still.add(1.0, 0.3, 1e-6);
  EXPECT_FALSE(still.solve(fit));
}

// Why a window spans a whole gear turn (docs/calibration.md section 5, "Windows shorter than a gear
// turn"). Over N readings uniform in angle across exactly one gear turn of the 20/40 pair (4 pi rad
// of pinion angle), every integer gear order is a whole number of periods, so the regressors (the
// mean, the shaft orders, the mesh harmonics) are orthogonal to any gear order the fit leaves out
// (discrete Fourier orthogonality): an unmodelled order moves no feature, and the mean's variance
// is sigma^2 / N as for the mean alone. Over a part of a turn the orthogonality is gone: an
// unmodelled gear 3x (pinion order 1.5), 2.5 or pinion 3x, 4x leaks into the mean and the mesh
// harmonics, and the shaft orders' regressors approach the mean's, so its variance grows. The table
// printed is the one in the docs (10000 readings per turn: 60 rpm at 5 kHz).
TEST(OrderRegression, OnlyWholeGearTurnsAreBlindToUnmodelledOrders) {
  // One fit over the fraction f of a gear turn of cos(order theta + phi) at pinion `order` (0:
  // none), or of cos(2 pi k phase + phi) at mesh harmonic `mesh` (0: none), or of uniform noise.
  auto fit = [](double f, double order, int mesh, double phi, bool noise) {
    OrderRegression reg(20, 40);
    const long n = std::lround(10000 * f);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uniform(-0.5, 0.5);
    for (long j = 0; j < n; ++j) {
      const double theta = 2.0 * kTwoPi * j / 10000.0 + 0.37, turns = 20.0 * theta / kTwoPi,
                   phase = turns - std::floor(turns);
      double y = 0.0;
      if (order > 0.0) y += std::cos(order * theta + phi);
      if (mesh > 0) y += std::cos(kTwoPi * mesh * phase + phi);
      if (noise) y += uniform(rng);
      reg.add(theta, phase, y);
    }
    OrderRegression::Fit out;
    EXPECT_TRUE(reg.solve(out)) << f;
    return std::make_pair(out, static_cast<double>(n));
  };
  struct Leak {
    double mean = 0.0, c1 = 0.0, c2 = 0.0;
  };
  // The largest leak over the unmodelled signal's phase: a leak is linear in (cos phi, sin phi).
  auto leak = [&](double f, double order, int mesh) {
    const OrderRegression::Fit a = fit(f, order, mesh, 0.0, false).first,
                               b = fit(f, order, mesh, 0.5 * kPi, false).first;
    return Leak{std::hypot(a.mean, b.mean),
                std::hypot(std::abs(a.harmonics[0]), std::abs(b.harmonics[0])),
                std::hypot(std::abs(a.harmonics[1]), std::abs(b.harmonics[1]))};
  };
  const int terms = OrderRegression(20, 40).terms();
  std::cout << "fraction of a gear turn | mean std x sqrt(N) / sigma | leak per unit amplitude "
               "into the mean (and |C_1|) of "
               "pinion order 1.5, 2.5, 3, 4 and mesh harmonic 5\n";
  for (const double f : {1.0, 0.98, 0.95, 0.9, 0.75, 0.5}) {
    const auto [noisy, n] = fit(f, 0.0, 0, 0.0, true);
    const double sigma =
        noisy.residual_rms * std::sqrt(n / (n - terms));  // the fit's own sigma estimate
    const double inflation = noisy.mean_std * std::sqrt(n) / sigma;
    std::cout << f << " | " << inflation << " |";
    double worst_mean = 0.0;
    for (const double order : {1.5, 2.5, 3.0, 4.0}) {
      const Leak l = leak(f, order, 0);
      std::cout << " " << l.mean << " (" << l.c1 << ")";
      worst_mean = std::max(worst_mean, l.mean);
      if (f == 1.0) {
        EXPECT_LT(l.mean, 1e-12) << order;
        EXPECT_LT(l.c1, 1e-12) << order;
        EXPECT_LT(l.c2, 1e-12) << order;
      }
    }
    const Leak l5 = leak(f, 0.0, 5);
    std::cout << " " << l5.mean << " (" << l5.c1 << ")\n";
    if (f == 1.0) {
      EXPECT_NEAR(inflation, 1.0, 1e-3);
      EXPECT_LT(l5.mean, 1e-12);
      EXPECT_LT(l5.c1, 1e-12);
    } else {
      EXPECT_GT(worst_mean, 1e-2) << f
                                  << ": a partial turn is not blind to an order the fit leaves out";
    }
    if (f == 0.5) {
      EXPECT_GT(inflation, 10.0)
          << "half a gear turn: pinion order 0.5 is half a period, near the mean's regressor";
    }
  }
}

/// Synthetic encoder readings of a rig with parameters `truth` (the static model's physics built
/// here from the mesh table and the supports): 120 rpm, 5 kHz, a torque staircase through the knee
/// and a reversal, 2^20-count encoders with 15 arcsec eccentricity each, 1 um manufacturing TE.
struct SyntheticRig {
  RigConfig rig;
  CalibrationVector truth;
  std::uint64_t seed = 1;
  double final_torque = 0.0;  ///< [N·m] a last level held for final_hold
  double final_hold = 0.0;    ///< [s]
  /// A departure from the static model that no parameter absorbs: the mesh deflection off by
  /// +level_error and -level_error on alternate torque levels.
  double level_error = 0.0;
};

/// The synthetic rig's mesh deflection at `phase` under the drive force `force` [N] with the
/// scissor preload force `fp` [N]: its truth's mesh scale on the unit-scale mesh table, in the
/// flank state the force puts it in (both flanks, the back path lifted, the drive flank lifted).
double trueMeshDeflection(const SyntheticRig& s, const AntiBacklashMesh& unit, double force,
                          double fp, double phase) {
  const CompositeMesh c = unit.at(phase, 0.0);
  const double k1 = s.truth[kMeshScale] * c.k1, k2 = s.truth[kMeshScale] * c.k2;
  const double kte = s.rig.anti_backlash.spring_stiffness, kc = kte * k2 / (kte + k2);
  double delta = force / (k1 + kc);
  if (force * kc > fp * (k1 + kc))
    delta = (force - fp) / k1;
  else if (force * k1 < -fp * (k1 + kc))
    delta = (force + fp) / kc;
  return delta;
}

/// The known rig of the recovery tests: mesh scale 1.12, both bearing scales 0.85, T_p 1.15 x the
/// drawing's, no TE offset.
SyntheticRig knownRig() {
  SyntheticRig s{seedRig(), {}, 3};
  s.truth << 1.12, 0.85, 0.85, 1.15 * s.rig.anti_backlash.preload_torque, 0.0;
  return s;
}

void runSweep(const SyntheticRig& s, Calibrator& calibrator, StiffnessEstimator& supports) {
  StaticTeModel physics(s.rig);
  const AntiBacklashMesh unit(s.rig.gears, s.rig.anti_backlash, s.rig.mesh_model,
                              s.rig.mesh_samples, 1.0);
  const double rbp = physics.baseRadius()[0], rbg = physics.baseRadius()[1];
  // Up to 1.5 x the knee, but at most 10 N·m: the seed's bearings reach the ISO 76 contact-pressure
  // limit near 11 N·m (1000 N radial preload plus ~2000 N of mesh force).
  const double top = std::min(1.5 * physics.kneeTorque(s.truth), 10.0);
  std::vector<double> levels = {0.0};
  for (int i = 1; i <= 10; ++i) levels.push_back(0.1 * i * top);
  for (int i = 1; i <= 4; ++i) levels.push_back(-0.25 * i);
  levels.push_back(0.0);
  std::vector<double> holds(levels.size(), 2.5);  // [s] 2.5 gear turns per level at 120 rpm
  if (s.final_hold > 0.0) {
    levels.push_back(s.final_torque);
    holds.push_back(s.final_hold);
  }
  std::mt19937_64 rng(s.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double arcsec = kTwoPi / (360.0 * 3600.0);
  const double ecc_p = (10.0 + 10.0 * uni(rng)) * arcsec, psi_p = kTwoPi * uni(rng);
  const double ecc_g = (10.0 + 10.0 * uni(rng)) * arcsec, psi_g = kTwoPi * uni(rng);
  const double count = kTwoPi / 1048576.0;  // 2^20 counts per turn
  const double speed = 120.0 * kTwoPi / 60.0, rate = 5000.0;
  const double fp = s.truth[kPreloadTorque] / rbg;
  MeasuredTeSample sample;
  long i = 0;
  for (std::size_t level = 0; level < levels.size(); ++level) {
    const double torque = levels[level], hold = holds[level];
    std::array<double, 2> d{};
    physics.shaftDeflection(torque, supports, d);
    const double bearings = d[0] / s.truth[kPinionBearingScale] + d[1] / s.truth[kGearBearingScale];
    const double force = torque / rbp;
    for (int j = 0; j < static_cast<int>(hold * rate); ++j, ++i) {
      const double t = i / rate, theta_p = speed * t;
      const double phase = 20.0 * theta_p / kTwoPi - std::floor(20.0 * theta_p / kTwoPi);
      double delta = trueMeshDeflection(s, unit, force, fp, phase);
      delta *= 1.0 + (level % 2 == 1 ? s.level_error : -s.level_error);
      const double x = delta + bearings + 1e-6 * std::sin(kTwoPi * phase) +
                       3e-5;  // manufacturing TE, encoder zero
      const double theta_g = (x - rbp * theta_p) / rbg;
      const double read_p =
          std::round((theta_p + ecc_p * std::sin(theta_p + psi_p)) / count) * count;
      const double read_g =
          std::round((theta_g + ecc_g * std::sin(theta_g + psi_g)) / count) * count;
      calibrator.reading(t, read_p, read_g, phase, speed, torque, supports, sample);
    }
  }
}

TEST(Calibrator, RecoversAKnownRigAndFlagsWhatEncodersCannotSeparate) {
  SyntheticRig s = knownRig();
  StiffnessEstimator supports(s.rig);
  Calibrator calibrator(s.rig);
  runSweep(s, calibrator, supports);
  const CalibrationEstimate& e = calibrator.estimate();
  ASSERT_GT(e.updates, 8u) << toString(e.outcome);
  EXPECT_EQ(e.baseline_windows, 4u);  // two gear turns at each of the two zero-torque levels
  std::cout << "estimate " << e.value.transpose() << "\nstd      " << e.std.transpose()
            << "\nupdates " << e.updates << " gated " << e.gated << " nis " << e.nis
            << " compliance " << e.series_compliance << " +- " << e.series_compliance_std << "\n";
  EXPECT_NEAR(e.value[kMeshScale] / s.truth[kMeshScale], 1.0, 0.05);
  EXPECT_NEAR(e.value[kPreloadTorque] / s.truth[kPreloadTorque], 1.0, 0.05);
  EXPECT_TRUE(e.identified[kMeshScale]);
  EXPECT_TRUE(e.identified[kPreloadTorque]);
  // The two shafts' bearings enter only as the sum of their compliances: neither alone is
  // identified...
  EXPECT_FALSE(e.identified[kPinionBearingScale]);
  EXPECT_FALSE(e.identified[kGearBearingScale]);
  // ...but the series compliance at the reference torque is, within 2 %.
  StaticTeModel physics(s.rig);
  std::array<double, 2> d{};
  physics.shaftDeflection(s.rig.calibration.reference_torque, supports, d);
  const double truth =
      (physics.features(s.truth, s.rig.calibration.reference_torque, d, 0.0, {0.0, 0.0})[0]) /
      physics.meshForce(s.rig.calibration.reference_torque);
  EXPECT_NEAR(e.series_compliance / truth, 1.0, 0.02);
  EXPECT_LT(std::abs(e.series_compliance - truth), 3.0 * e.series_compliance_std + 1e-15);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(e.natural_frequency_low[i], e.natural_frequency[i]);
    EXPECT_GT(e.natural_frequency_high[i], e.natural_frequency[i]);
  }
}

TEST(Calibrator, BandsWidenOnlyWhereTheWindowsShowMoreModelErrorThanAllowed) {
  // The synthetic rig as it is departs from the calibrator's model by 1e-4 to 1e-3 of a feature
  // (section 6 of docs/calibration.md), within the default 1 % allowance: the filter's own
  // covariance is reported. With the mesh deflection off by +-2 % on alternate torque levels,
  // twice the allowance and nothing a parameter can absorb, the windows show it (c > 1) and the
  // bands widen.
  SyntheticRig s = knownRig();
  for (double level_error : {0.0, 0.02}) {
    s.level_error = level_error;
    StiffnessEstimator supports(s.rig);
    Calibrator calibrator(s.rig);
    runSweep(s, calibrator, supports);
    const CalibrationEstimate& e = calibrator.estimate();
    const CalibrationMatrix filter = calibrator.filterCovariance();
    std::cout << "level error " << level_error << ": model_error_scale "
              << e.model_error_scale.transpose() << ", updates " << e.updates << ", gated "
              << e.gated << "\n  std          " << e.std.transpose() << "\n  filter's std "
              << filter.diagonal().cwiseSqrt().transpose() << "\n";
    if (level_error == 0.0) {
      EXPECT_LT(e.model_error_scale.maxCoeff(), 1.0);
      EXPECT_EQ(calibrator.covariance(), filter);  // the filter's own, bit for bit
    } else {
      EXPECT_GT(e.model_error_scale.maxCoeff(), 1.0);
      for (int i = 0; i < kCalibrationSize; ++i)
        EXPECT_GE(calibrator.covariance()(i, i), (1.0 - 1e-9) * filter(i, i)) << i;
      EXPECT_GT(e.std[kMeshScale], std::sqrt(filter(kMeshScale, kMeshScale)));
    }
  }
}

/// After runSweep: one window's readings (a gear turn and 2 % more) of the same rig at a steady
/// `torque` [N·m], from a fresh stretch (the calibrator interrupted first, as a reset does), at
/// `speed` [rad/s] and `rate` [Hz] readings, 2^20-count encoders, with `te_error` [m] added to
/// every reading's TE (a stretch of bad data). Stops at the reading that closes the window; returns
/// the readings' result flags together.
int feedWindow(const SyntheticRig& s, Calibrator& calibrator, StiffnessEstimator& supports,
               double t0, double torque, double speed, double rate, double te_error) {
  StaticTeModel physics(s.rig);
  const AntiBacklashMesh unit(s.rig.gears, s.rig.anti_backlash, s.rig.mesh_model,
                              s.rig.mesh_samples, 1.0);
  const double rbp = physics.baseRadius()[0], rbg = physics.baseRadius()[1];
  std::array<double, 2> d{};
  physics.shaftDeflection(torque, supports, d);
  const double bearings = d[0] / s.truth[kPinionBearingScale] + d[1] / s.truth[kGearBearingScale];
  const double force = torque / rbp, fp = s.truth[kPreloadTorque] / rbg;
  const double count = kTwoPi / 1048576.0;
  const double gear_turn =
      kTwoPi * s.rig.gears.teeth[1] / s.rig.gears.teeth[0];  // [rad] of the pinion
  const long n = static_cast<long>(std::ceil(1.02 * gear_turn / (speed / rate)));
  calibrator.interrupt();
  MeasuredTeSample sample;
  int flags = 0;
  for (long j = 0; j <= n; ++j) {
    const double t = t0 + j / rate, theta_p = speed * (j / rate);
    const double phase = 20.0 * theta_p / kTwoPi - std::floor(20.0 * theta_p / kTwoPi);
    const double x = trueMeshDeflection(s, unit, force, fp, phase) + bearings +
                     1e-6 * std::sin(kTwoPi * phase) + 3e-5 + te_error;
    const double theta_g = (x - rbp * theta_p) / rbg;
    flags |= calibrator.reading(t, std::round(theta_p / count) * count,
                                std::round(theta_g / count) * count, phase, speed, torque, supports,
                                sample);
    if (flags & Calibrator::kWindow) break;  // the window closed: nothing after it
  }
  return flags;
}

TEST(Calibrator, BadStretchesAfterConvergenceLeaveTheEstimate) {
  // Gate outliers, freeze updates when the excitation is too poor, and never let a bad
  // stretch of data drive the estimate. After a converged sweep, each window below closes
  // (kWindow) and leaves every parameter and its std exactly as they were, counted as gated or
  // not excited with its reason; a good window afterwards still updates.
  SyntheticRig s = knownRig();
  StiffnessEstimator supports(s.rig);
  Calibrator calibrator(s.rig);
  runSweep(s, calibrator, supports);
  const CalibrationEstimate converged = calibrator.estimate();
  ASSERT_TRUE(converged.identified[kMeshScale] && converged.identified[kPreloadTorque]);
  const double rpm = kTwoPi / 60.0;  // [rad/s] per rpm
  struct Case {
    const char* what;
    double speed, rate, te_error;
    WindowOutcome outcome;
  };
  // The seed servo's lowest mode is about 7.9 kHz (docs/resonance.md): quasi-static up to a mesh
  // frequency of 790 Hz (max_mesh_to_natural 0.1), 2370 rpm with z_p = 20.
  const Case cases[] = {
      {"a 20 um step in the measured TE (10x the load's TE at 3 N m)", 120.0 * rpm, 5000.0, 2e-5,
       WindowOutcome::kGated},
      {"2 rpm, below min_speed_rpm = 5", 2.0 * rpm, 1000.0, 0.0, WindowOutcome::kTooSlow},
      {"3000 rpm: mesh at 1 kHz, above 0.1 of the lowest mode", 3000.0 * rpm, 50000.0, 0.0,
       WindowOutcome::kNotQuasiStatic},
      {"500 rpm read at 500 Hz: the second mesh harmonic (333 Hz) above 0.45 of it", 500.0 * rpm,
       500.0, 0.0, WindowOutcome::kTooSparse},
  };
  double t0 = 1000.0;
  std::uint64_t gated = converged.gated, not_excited = converged.not_excited;
  for (const Case& c : cases) {
    const int flags = feedWindow(s, calibrator, supports, t0, 3.0, c.speed, c.rate, c.te_error);
    t0 += 200.0;
    const CalibrationEstimate& e = calibrator.estimate();
    EXPECT_TRUE(flags & Calibrator::kWindow) << c.what << ": no window closed";
    EXPECT_EQ(e.outcome, c.outcome) << c.what << ": " << toString(e.outcome);
    EXPECT_EQ(e.value, converged.value) << c.what;
    EXPECT_EQ(e.std, converged.std) << c.what;
    EXPECT_EQ(e.updates, converged.updates) << c.what;
    if (c.outcome == WindowOutcome::kGated) {
      EXPECT_EQ(e.gated, ++gated) << c.what;
      EXPECT_GT(e.nis, s.rig.calibration.gate) << c.what;
      EXPECT_TRUE(e.excited) << c.what << ": the excitation sufficed; the data did not";
    } else {
      EXPECT_EQ(e.not_excited, ++not_excited) << c.what;
      EXPECT_FALSE(e.excited) << c.what;
    }
  }
  EXPECT_EQ(
      feedWindow(s, calibrator, supports, t0, 3.0, 120.0 * rpm, 5000.0, 0.0) & Calibrator::kWindow,
      Calibrator::kWindow);
  EXPECT_EQ(calibrator.estimate().outcome, WindowOutcome::kUpdated)
      << toString(calibrator.estimate().outcome);
  EXPECT_EQ(calibrator.estimate().updates, converged.updates + 1);
}

// A calibration that has not started says why, with the window rule's numbers (calibrator.hpp): a
// window spans one gear turn of pinion angle at a steady torque. The seed's 20/40 pair turns its
// gear once per 4 pi rad of pinion angle: 2 s at 60 rpm. Each stretch below is a steady torque
// ended by a break in the readings (interrupt(): the torque filter restarts at the next reading's
// torque), so it starts settled and spans exactly its readings: (n - 1) / rate seconds and
// w (n - 1) / rate of pinion angle.
TEST(CalibratorProgress, SaysHowFarTheLongestSteadyTorqueFellShortOfAWindow) {
  const RigConfig rig = seedRig();
  ASSERT_EQ(rig.gears.teeth[0], 20);
  ASSERT_EQ(rig.gears.teeth[1], 40);
  StiffnessEstimator supports(rig);
  Calibrator calibrator(rig);
  EXPECT_EQ(calibrator.waitingReason(),
            "no encoder reading with the gear angle has reached the calibration");
  const double w = kTwoPi, rate = 5000.0;  // 60 rpm [rad/s], readings [Hz]
  MeasuredTeSample sample;
  long k = 0;  // readings so far: the time and the angle go on across the breaks
  auto hold = [&](double torque, long n) {
    for (long j = 0; j < n; ++j, ++k) {
      const double t = k / rate, theta = w * t, turns = 20.0 * theta / kTwoPi;
      calibrator.reading(t, theta, -0.5 * theta, turns - std::floor(turns), w, torque, supports,
                         sample);
    }
  };
  hold(0.0, 6000);  // 1.2 s unloaded
  calibrator.interrupt();
  hold(2.0, 9500);  // 1.9 s at 2 N m
  calibrator.interrupt();
  hold(3.0, 5000);  // 1 s at 3 N m, still open
  CalibrationProgress p = calibrator.progress();
  EXPECT_EQ(calibrator.estimate().windows, 0u);
  EXPECT_EQ(p.readings, 20500u);
  EXPECT_NEAR(p.window_angle, 2.0 * kTwoPi, 1e-15);
  EXPECT_NEAR(p.windowSeconds(w), 2.0, 1e-15);
  EXPECT_EQ(p.unloaded.readings, 6000);
  EXPECT_NEAR(p.unloaded.duration, 5999.0 / rate, 1e-12);
  EXPECT_EQ(p.loaded.readings, 9500);
  EXPECT_NEAR(p.loaded.duration, 9499.0 / rate, 1e-12);
  EXPECT_NEAR(p.loaded.angle, w * 9499.0 / rate, 1e-9);
  EXPECT_EQ(p.loaded.torque, 2.0);
  EXPECT_NEAR(p.loaded.speed, w, 1e-11);  // the mean of 9500 equal speeds: rounding only
  EXPECT_EQ(p.smallest_torque, 0.0);
  // 1.8998 s is 0.9499 of the 2 s a gear turn takes at 60 rpm.
  EXPECT_EQ(calibrator.waitingReason(),
            "no window closed: the longest steady torque (2 N*m) lasted 1.90 s, 0.95 of a gear "
            "turn, and a window needs one "
            "gear turn, 2.00 s at 60 rpm");
  // The open stretch counts as it grows: at 1.95 s it is the longest.
  hold(3.0, 4750);
  p = calibrator.progress();
  EXPECT_EQ(p.loaded.readings, 9750);
  EXPECT_EQ(p.loaded.torque, 3.0);
  EXPECT_NEAR(p.loaded.duration, 9749.0 / rate, 1e-12);
  // Past a gear turn the window closes (10000 intervals span 4 pi to rounding; one more spans
  // more): a loaded window without a baseline.
  hold(3.0, 252);
  EXPECT_EQ(calibrator.estimate().windows, 1u);
  EXPECT_EQ(calibrator.estimate().outcome, WindowOutcome::kNoBaseline);
  p = calibrator.progress();
  EXPECT_EQ(p.count(WindowOutcome::kNoBaseline), 1u);
  EXPECT_EQ(p.loaded_windows, 1u);
  EXPECT_EQ(calibrator.waitingReason(),
            "no window updated the calibration (1 window closed: 1 before any baseline); no "
            "unloaded baseline window: the "
            "longest steady unloaded torque (0 N*m) lasted 1.20 s, 0.60 of a gear turn, and a "
            "window needs one gear turn, "
            "2.00 s at 60 rpm");
}

// Windows that closed without updating: each kind says what decided it, against its limit. The
// numbers are the rules' own closed forms (calibrator.cpp, Calibrator::excitation): 2 rpm against
// min_speed_rpm 5; 3000 rpm puts the mesh (z_p = 20) at 1000 Hz against 0.1 of the lowest natural
// frequency; 500 rpm read at 500 Hz puts the second mesh harmonic at 333 Hz, which needs a
// reading rate above 2 x 166.7 / 0.45 = 740.7 Hz; a 20 um step in the TE, ten times the load's TE
// at 3 N m, is gated (its NIS is the estimate's).
TEST(CalibratorProgress, SaysWhyClosedWindowsDidNotUpdate) {
  SyntheticRig s = knownRig();
  StiffnessEstimator supports(s.rig);
  Calibrator calibrator(s.rig);
  const double rpm = kTwoPi / 60.0;  // [rad/s] per rpm
  const CalibrationConfig& c = s.rig.calibration;
  ASSERT_TRUE(feedWindow(s, calibrator, supports, 0.0, 3.0, 120.0 * rpm, 5000.0, 0.0) &
              Calibrator::kWindow);
  ASSERT_EQ(calibrator.estimate().outcome, WindowOutcome::kNoBaseline);
  EXPECT_EQ(calibrator.waitingReason(),
            "no window updated the calibration (1 window closed: 1 before any baseline); no torque "
            "was held at |T| <= "
            "~baseline_torque = 0.05 N*m for the unloaded baseline (the smallest: 3 N*m)");
  ASSERT_TRUE(feedWindow(s, calibrator, supports, 10.0, 0.0, 120.0 * rpm, 5000.0, 0.0) &
              Calibrator::kWindow);
  ASSERT_EQ(calibrator.estimate().outcome, WindowOutcome::kBaseline);
  ASSERT_TRUE(feedWindow(s, calibrator, supports, 20.0, 3.0, 2.0 * rpm, 1000.0, 0.0) &
              Calibrator::kWindow);
  ASSERT_TRUE(feedWindow(s, calibrator, supports, 200.0, 3.0, 3000.0 * rpm, 50000.0, 0.0) &
              Calibrator::kWindow);
  ASSERT_TRUE(feedWindow(s, calibrator, supports, 210.0, 3.0, 500.0 * rpm, 500.0, 0.0) &
              Calibrator::kWindow);
  ASSERT_TRUE(feedWindow(s, calibrator, supports, 220.0, 3.0, 120.0 * rpm, 5000.0, 2e-5) &
              Calibrator::kWindow);
  const CalibrationEstimate& e = calibrator.estimate();
  ASSERT_EQ(e.updates, 0u);
  ASSERT_EQ(e.outcome, WindowOutcome::kGated);
  const CalibrationProgress p = calibrator.progress();
  for (WindowOutcome o :
       {WindowOutcome::kNoBaseline, WindowOutcome::kBaseline, WindowOutcome::kTooSlow,
        WindowOutcome::kNotQuasiStatic, WindowOutcome::kTooSparse, WindowOutcome::kGated}) {
    EXPECT_EQ(p.count(o), 1u) << toString(o);
  }
  EXPECT_EQ(p.count(WindowOutcome::kUpdated), 0u);
  EXPECT_EQ(p.loaded_windows, 5u);
  const auto at = [](WindowOutcome o) { return static_cast<std::size_t>(o); };
  EXPECT_NEAR(p.value[at(WindowOutcome::kTooSlow)], 2.0, 1e-9);
  EXPECT_EQ(p.limit[at(WindowOutcome::kTooSlow)], c.min_speed_rpm);
  EXPECT_NEAR(p.value[at(WindowOutcome::kNotQuasiStatic)], 1000.0, 1e-9);
  EXPECT_NEAR(p.limit[at(WindowOutcome::kNotQuasiStatic)],
              c.max_mesh_to_natural * e.natural_frequency[0], 1e-9);
  EXPECT_NEAR(p.value[at(WindowOutcome::kTooSparse)], 500.0, 1e-6);
  EXPECT_NEAR(p.limit[at(WindowOutcome::kTooSparse)], 2.0 * (500.0 * 20.0 / 60.0) / 0.45, 1e-9);
  EXPECT_GT(p.value[at(WindowOutcome::kGated)], c.gate);
  EXPECT_EQ(p.value[at(WindowOutcome::kGated)], e.nis);
  const std::string why = calibrator.waitingReason();
  std::cout << why << "\n";
  EXPECT_EQ(why.find("no window updated the calibration (6 windows closed: 1 baseline, 1 gated, 1 "
                     "before any baseline, 1 too "
                     "slow, 1 not quasi-static, 1 too sparse); "),
            0u)
      << why;
  for (const char* part : {"1 window too slow: the last at 2 rpm, below ~min_speed_rpm = 5",
                           "1 window not quasi-static: the last at a mesh frequency of 1000 Hz, "
                           "above ~max_mesh_to_natural x the lowest natural frequency = ",
                           "1 window too sparse: the last read at 500 Hz, and its second mesh "
                           "harmonic needs more than 740.7 Hz",
                           "1 window gated: the last one's normalised innovation squared "}) {
    EXPECT_NE(why.find(part), std::string::npos) << part << "\nin: " << why;
  }
  EXPECT_EQ(why.find("no unloaded baseline"), std::string::npos) << "a baseline exists";
  EXPECT_EQ(why.find("no loaded window closed"), std::string::npos) << "loaded windows closed";
  // A good window updates: nothing left to explain.
  ASSERT_TRUE(feedWindow(s, calibrator, supports, 230.0, 3.0, 120.0 * rpm, 5000.0, 0.0) &
              Calibrator::kWindow);
  ASSERT_EQ(calibrator.estimate().outcome, WindowOutcome::kUpdated);
  EXPECT_EQ(calibrator.waitingReason(), "");
  EXPECT_EQ(calibrator.progress().count(WindowOutcome::kUpdated), 1u);
}

TEST(Calibrator, ACalibratedGearboxStillSaysWhatTheDataDetermine) {
  // drivetrain_replay --calibrate (calibrated_gearbox.cpp) writes the posterior as the next run's
  // prior (its std where identified, the drawing's spread where not) and keeps the drawing's spread
  // as reference_std. A second run over the same rig then flags the mesh scale and T_p identified
  // again, and the bearing scales still not: `identified` is judged against the drawing's spread.
  // Without reference_std the same run would call the mesh scale and T_p not identified, because
  // nothing halves a std the first run already shrank.
  SyntheticRig s = knownRig();
  StiffnessEstimator supports(s.rig);
  Calibrator first(s.rig);
  runSweep(s, first, supports);
  const CalibrationEstimate& e1 = first.estimate();
  ASSERT_TRUE(e1.identified[kMeshScale] && e1.identified[kPreloadTorque]);
  const auto calibrated = [&](bool keep_reference) {
    RigConfig rig = s.rig;
    CalibrationConfig& c = rig.calibration;
    CalibrationPrior* p[kCalibrationSize] = {&c.mesh_stiffness_scale, &c.pinion_bearing_scale,
                                             &c.gear_bearing_scale, &c.preload_torque,
                                             &c.te_offset};
    for (int i = 0; i < kCalibrationSize; ++i) {
      double drawing = p[i]->reference();
      if (i == kPinionBearingScale ||
          i == kGearBearingScale) {  // kept in compliance, as the writer does
        drawing *= (e1.value[i] / p[i]->mean) * (e1.value[i] / p[i]->mean);
      }
      *p[i] = CalibrationPrior{e1.value[i], e1.identified[i] ? e1.std[i] : drawing,
                               keep_reference ? drawing : -1.0};
    }
    return rig;
  };
  s.seed = 5;  // new encoder errors
  for (const bool keep : {true, false}) {
    const RigConfig rig = calibrated(keep);
    Calibrator second(rig);
    runSweep(s, second, supports);
    const CalibrationEstimate& e2 = second.estimate();
    ASSERT_GT(e2.updates, 8u);
    EXPECT_NEAR(e2.value[kMeshScale] / s.truth[kMeshScale], 1.0, 0.05);
    EXPECT_NEAR(e2.value[kPreloadTorque] / s.truth[kPreloadTorque], 1.0, 0.05);
    EXPECT_LE(e2.std[kMeshScale], e1.std[kMeshScale]) << "the second run adds information";
    EXPECT_EQ(e2.identified[kMeshScale], keep) << (keep ? "with" : "without") << " reference_std";
    EXPECT_EQ(e2.identified[kPreloadTorque], keep)
        << (keep ? "with" : "without") << " reference_std";
    EXPECT_FALSE(e2.identified[kPinionBearingScale]);
    EXPECT_FALSE(e2.identified[kGearBearingScale]);
  }
}

TEST(Calibrator, NoDriftOverTenMinutesAtConstantLoad) {
  // The stability target: after the sweep, 10 min at one steady load move no parameter by
  // more than one (final) standard deviation. The readings keep their noise (encoder counts).
  SyntheticRig s{seedRig(), {}, 11};
  s.truth << 0.9, 1.1, 1.2, 0.9 * s.rig.anti_backlash.preload_torque, 0.0;
  StiffnessEstimator supports(s.rig);
  Calibrator swept(s.rig);
  runSweep(s, swept, supports);
  const CalibrationEstimate before = swept.estimate();
  s.final_torque = 3.0;
  s.final_hold = 600.0;
  Calibrator held(s.rig);
  runSweep(s, held, supports);
  const CalibrationEstimate& after = held.estimate();
  EXPECT_GT(after.updates, before.updates + 500);  // ~600 gear turns, each a window
  for (int i = 0; i < kCalibrationSize; ++i) {
    EXPECT_LE(std::abs(after.value[i] - before.value[i]), after.std[i] + before.std[i] * 1e-9)
        << calibrationName(i);
  }
}

}  // namespace
}  // namespace drivetrain_stiffness

namespace drivetrain_stiffness {
namespace {

// docs/calibration.md, "Monte Carlo": 50 rigs drawn from the ranges (mesh scale 0.8-1.2,
// each bearing scale 0.7-1.3, T_p +-20 %), each swept once with its own encoder errors. The 95 %
// bounds must cover the truth in at least 90 % of the rigs (45 of 50).
TEST(CalibratorMonteCarlo, ErrorsAndCoverageOverFiftyPerturbedRigs) {
  // The readings come from the calibrator's own static model here, so the default 1 % model-error
  // allowance makes the bounds conservative (all 50 cover: docs/calibration.md). Without it the
  // sequential filter is overconfident on the knee's nonlinearity (T_p off by up to 28 %, coverage
  // 25 of 50, measured): the allowance stays, and this test holds the errors and a coverage >= 90
  // %.
  const RigConfig rig = seedRig();
  std::mt19937_64 draw(2026);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  int covered_mesh = 0, covered_tp = 0, covered_compliance = 0, runs = 0;
  double worst_mesh = 0.0, worst_tp = 0.0, worst_compliance = 0.0;
  for (int run = 0; run < 50; ++run, ++runs) {
    SyntheticRig s{rig, {}, static_cast<std::uint64_t>(100 + run)};
    s.truth << 0.8 + 0.4 * uni(draw), 0.7 + 0.6 * uni(draw), 0.7 + 0.6 * uni(draw),
        rig.anti_backlash.preload_torque * (0.8 + 0.4 * uni(draw)), 0.0;
    StiffnessEstimator supports(s.rig);
    Calibrator calibrator(s.rig);
    runSweep(s, calibrator, supports);
    const CalibrationEstimate& e = calibrator.estimate();
    StaticTeModel physics(s.rig);
    std::array<double, 2> d{};
    const double tr = s.rig.calibration.reference_torque;
    physics.shaftDeflection(tr, supports, d);
    const double compliance =
        physics.features(s.truth, tr, d, 0.0, {0.0, 0.0})[0] / physics.meshForce(tr);
    const double em = std::abs(e.value[kMeshScale] / s.truth[kMeshScale] - 1.0);
    const double et = std::abs(e.value[kPreloadTorque] / s.truth[kPreloadTorque] - 1.0);
    const double ec = std::abs(e.series_compliance / compliance - 1.0);
    worst_mesh = std::max(worst_mesh, em);
    worst_tp = std::max(worst_tp, et);
    worst_compliance = std::max(worst_compliance, ec);
    covered_mesh +=
        std::abs(e.value[kMeshScale] - s.truth[kMeshScale]) <= 1.959964 * e.std[kMeshScale];
    covered_tp += std::abs(e.value[kPreloadTorque] - s.truth[kPreloadTorque]) <=
                  1.959964 * e.std[kPreloadTorque];
    covered_compliance +=
        std::abs(e.series_compliance - compliance) <= 1.959964 * e.series_compliance_std;
    // What encoders cannot split stays unidentified whatever the truth; what they see is
    // identified.
    EXPECT_FALSE(e.identified[kPinionBearingScale]) << run;
    EXPECT_FALSE(e.identified[kGearBearingScale]) << run;
    EXPECT_TRUE(e.identified[kMeshScale]) << run;
    EXPECT_TRUE(e.identified[kPreloadTorque]) << run;
  }
  std::cout << "worst error: mesh " << worst_mesh << " T_p " << worst_tp << " compliance "
            << worst_compliance << "\ncovered of " << runs << ": mesh " << covered_mesh << " T_p "
            << covered_tp << " compliance " << covered_compliance << "\n";
  EXPECT_LT(worst_mesh, 0.05);
  EXPECT_LT(worst_tp, 0.05);
  EXPECT_LT(worst_compliance, 0.02);
  for (int covered : {covered_mesh, covered_tp, covered_compliance}) EXPECT_GE(covered, 45);
}

}  // namespace
}  // namespace drivetrain_stiffness

namespace drivetrain_stiffness {
namespace {

struct CalibrationSink : PipelineSink {
  std::vector<MeasuredTeSample> samples;
  std::vector<CalibrationEstimate> estimates;
  void measuredTe(Stamp, const MeasuredTeSample& s) override { samples.push_back(s); }
  void calibration(Stamp, const CalibrationEstimate& e) override { estimates.push_back(e); }
};

// The calibration rule through the pipeline: torque at 1 kHz, joint_states with both joints at 5
// kHz carrying the nominal rig's static TE; the baseline at 0 N·m, then 2 N·m. The processed
// measured TE must match the model's prediction (the rig is the model here) to the encoder's
// resolution.
TEST(RigPipelineCalibration, EncoderReadingsReachTheCalibratorAndTheSink) {
  RigConfig rig = seedRig();
  RigPipeline pipeline(rig, PipelineOptions{});
  ASSERT_NE(pipeline.calibrator(), nullptr);
  CalibrationSink sink;
  const test::StaticTeEncoder encoder(rig, 2.0);
  const StaticTeModel& model = encoder.model();
  const CalibrationVector& p = encoder.parameters();
  const double w = 120.0 / 60.0 * kTwoPi, count = kTwoPi / 1048576.0;  // 2^20 counts per turn
  for (int k = 0; k < 40000; ++k) {                                    // 8 s at 5 kHz
    const double t = 2e-4 * k, torque = t < 3.0 ? 0.0 : 2.0;
    if (k % 5 == 0) pipeline.torque(Stamp{test::kEpoch + 200000LL * k}, torque, sink);
    pipeline.motion(Stamp{test::kEpoch + 200000LL * k + 100000LL},
                    encoder.reading(w * t, w, torque, count), sink);
  }
  const PipelineCounters& c = pipeline.counters();
  EXPECT_EQ(c.calibration_out, sink.estimates.size());
  EXPECT_EQ(c.measured_te_out, sink.samples.size());
  EXPECT_EQ(c.calibration_errors, 0u);
  const CalibrationEstimate& last = sink.estimates.back();
  // One window per gear turn (1 s at 120 rpm): 0-1 s and 1-2 s at 0 N·m (the third is cut by the
  // torque step at 3 s, a few readings short of a turn), then 3-4 ... 6-7 s at 2 N·m.
  ASSERT_EQ(sink.estimates.size(), 6u);
  EXPECT_EQ(last.baseline_windows, 2u);
  EXPECT_EQ(last.updates, 4u);
  EXPECT_EQ(last.gated, 0u);
  EXPECT_NEAR(last.value[kMeshScale], 1.0, 0.01);
  // Loaded readings: the processed TE equals the prediction within a few encoder counts at the
  // gear's radius (2 pi r_b,g / 2^20 = 68 nm), except where one count moves the reading across a
  // tooth switch (the stiffness jumps there: ~1.5 um of TE at 2 N·m), a few readings per period.
  double sum2 = 0.0;
  long readings = 0, beyond = 0;
  for (const MeasuredTeSample& s : sink.samples) {
    ASSERT_TRUE(std::isfinite(s.te) && std::isfinite(s.predicted) && std::isfinite(s.residual));
    if (s.torque != 2.0) continue;
    ++readings;
    sum2 += s.residual * s.residual;
    beyond += std::abs(s.residual) > 0.3e-6;
  }
  ASSERT_GT(readings, 20000);
  EXPECT_LT(std::sqrt(sum2 / readings), 0.1e-6);
  EXPECT_LT(beyond, readings / 100);
  // The mean TE at 2 N·m is ~11 um: the residual is below 3 % of it everywhere.
  EXPECT_GT(model.features(p, 2.0, encoder.loadedShafts(), 0.0, encoder.zeroShafts())[0], 10e-6);
}

// The recording of the issue that asked for this: 60 rpm, torque steps of 2 s, exactly one gear
// turn of the 20/40 pair, through the pipeline (torque at 1 kHz, joint_states at 5 kHz). A step
// starts a new window only once the 20 ms torque filter has come within the band (~torque_band
// 0.02 N m + 1 %) of the new torque: from 0 to 2 N m that takes at least tau ln(2 / 0.04) =
// 78 ms, and e^-10 of the step is reached after 10 tau = 0.2 s. So no loaded stretch spans a
// whole turn: it lasts between 2 - 0.2 and 2 - 0.078 s (plus the reading or two after the next
// step that the filter takes to leave the band, 0.4 ms), and the unloaded 2.4 s at the start
// closes the baseline window and nothing more. The same rig with 4 s steps calibrates, and then
// there is nothing to explain.
TEST(RigPipelineCalibration, TwoSecondStepsAtSixtyRpmSayWhyNoWindowCloses) {
  const RigConfig rig = seedRig();
  const test::StaticTeEncoder encoder(rig, 2.0);
  const double w = kTwoPi;  // [rad/s] 60 rpm: a gear turn (4 pi rad of pinion angle) in 2 s
  auto run = [&](double step) {
    RigPipeline pipeline(rig, PipelineOptions{});
    CalibrationSink sink;
    const double end = 2.4 + 5.0 * step;     // 2.4 s unloaded, then 2, 0, 2, 0, 2 N m
    for (long k = 0; 2e-4 * k < end; ++k) {  // 5 kHz
      const double t = 2e-4 * k;
      const int level = t < 2.4 ? -1 : static_cast<int>((t - 2.4) / step);
      const double torque = level >= 0 && level % 2 == 0 ? 2.0 : 0.0;
      if (k % 5 == 0) pipeline.torque(Stamp{test::kEpoch + 200000LL * k}, torque, sink);
      pipeline.motion(Stamp{test::kEpoch + 200000LL * k + 100000LL},
                      encoder.reading(w * t, w, torque), sink);
    }
    return std::make_pair(
        pipeline.calibrator()->estimate(),
        std::make_pair(pipeline.calibrator()->progress(), pipeline.calibrator()->waitingReason()));
  };
  const auto [e2, explained2] = run(2.0);
  const auto& [p, why] = explained2;
  EXPECT_EQ(e2.windows, 1u);
  EXPECT_EQ(e2.baseline_windows, 1u);
  EXPECT_EQ(e2.updates, 0u);
  EXPECT_EQ(p.loaded_windows, 0u);
  // The readings up to the one the filter leaves the band at already hold the next step's 0 N m:
  // at most 4 of the ~9600 (0.6 ms at 5 kHz, plus one).
  EXPECT_LE(p.loaded.torque, 2.0);
  EXPECT_GT(p.loaded.torque, 2.0 * (1.0 - 4.0 / 9000.0));
  EXPECT_NEAR(p.loaded.speed, w, 1e-11);
  EXPECT_GT(p.loaded.duration, 2.0 - 10.0 * 0.02);
  EXPECT_LT(p.loaded.duration, 2.0 - 0.02 * std::log(2.0 / 0.04) + 6e-4);
  // The stamps' time is seconds since 1970 in a double (2.4e-7 s apart at 2026): the span of angle
  // and the span of time agree to that.
  EXPECT_NEAR(p.loaded.angle, w * p.loaded.duration, w * 5e-7);
  EXPECT_NEAR(p.windowSeconds(p.loaded.speed), 2.0, 1e-12);
  char expected[256];
  std::snprintf(expected, sizeof expected,
                "no window updated the calibration (1 window closed: 1 baseline); no loaded window "
                "closed: the longest steady "
                "loaded torque (2 N*m) lasted %.2f s, %.2f of a gear turn, and a window needs one "
                "gear turn, 2.00 s at 60 rpm",
                p.loaded.duration, p.loaded.angle / (2.0 * kTwoPi));
  EXPECT_EQ(why, expected);
  std::cout << why << "\n";

  const auto [e4, explained4] = run(4.0);
  EXPECT_EQ(e4.baseline_windows, 1u + 2u);  // 2.4 s, and one turn of each 4 s zero step
  EXPECT_GE(e4.updates, 3u);                // one turn of each 4 s step at 2 N m
  EXPECT_EQ(explained4.second, "");
}
}  // namespace
}  // namespace drivetrain_stiffness

// The model's inputs and ownership: the measured torque as the model's input (against seed 000
// eq 14 and against the same torque as a constant profile), the rig excitation known by type
// (refusals where there is none), and an exact propagator independent of the model it was built
// from.
#include <gtest/gtest.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {
const RigConfig& rig() { return test::seedServo(); }

std::shared_ptr<const AntiBacklashMesh> mesh() {
  static const auto m = std::make_shared<const AntiBacklashMesh>(rig());
  return m;
}

GearRotorParameters params() { return rigRotorParameters(rig(), *mesh(), {1.2e8, 1.2e8}); }

// The online estimator's excitation (balanced load, 1000 rpm, 1 um TE) with the given torque kind.
std::shared_ptr<RigExcitation> excitation(TorqueProfile::Kind kind, double mean) {
  RigExcitationSpec s;
  s.speed = 1000.0 * kTwoPi / 60.0;
  s.te_amplitude = 1e-6;
  s.balanced_load = true;
  s.torque.kind = kind;
  s.torque.mean = mean;
  return std::make_shared<RigExcitation>(mesh(), params(), s);
}
}  // namespace

// The drive force of a held torque: F = T / r_p with the load following the input (seed 000 eq 14
// with T_g = T_p r_g / r_p, docs/model.md), r_p = 5.638 mm for the seed pair (m 0.6 mm, 20 teeth, 20 deg).
TEST(ModelInputs, TorqueInputGivesTheBalancedDriveForce) {
  GearRotorModel model(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  ASSERT_NE(model.rigExcitation(), nullptr);
  model.setTorqueInput(0.4);
  EXPECT_EQ(model.torqueInput(), 0.4);
  MeshInstant m;
  model.meshAt(1.3e-3, m);
  EXPECT_NEAR(m.drive_force, 0.4 / 5.6382e-3, 1e-4 * 70.9);
  EXPECT_NEAR(model.forces(1.3e-3, State6::Zero()).drive_force, 0.4 / 5.6382e-3, 1e-4 * 70.9);
  // The excitation alone has no torque of its own (the model puts the input in).
  model.excitation().at(1.3e-3, m);
  EXPECT_EQ(m.drive_force, 0.0);
}

// A held input is the same model as a constant profile at that torque: the same static
// equilibrium and the same dopri5 trajectory, to the bit (the same arithmetic).
TEST(ModelInputs, TorqueInputMatchesAConstantProfile) {
  GearRotorModel held(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  held.setTorqueInput(0.25);
  const GearRotorModel constant(params(), excitation(TorqueProfile::Kind::kConstant, 0.25));
  const State6 y0 = staticEquilibrium(held, 0.0);
  EXPECT_EQ(y0, staticEquilibrium(constant, 0.0));
  // The start carries the torque on the mesh spring: k_s delta = T / r_p = 44.3 N (seed 000 eq 14;
  // the mesh force itself also has the damper against the TE's rate, largest at t = 0).
  MeshInstant m;
  held.meshAt(0.0, m);
  EXPECT_NEAR((m.k_drive + m.k_back) * held.forces(0.0, y0).delta, 0.25 / 5.6382e-3, 1e-4 * 44.3);
  IntegratorOptions o;
  const State6 a = integrate(held, IntegratorMethod::kDopri5, o, 0.0, y0, 6e-3, 1e-3, nullptr);
  const State6 b = integrate(constant, IntegratorMethod::kDopri5, o, 0.0, y0, 6e-3, 1e-3, nullptr);
  EXPECT_EQ(a, b);
}

// Only a model whose profile is kInput takes a torque input; only a rig's model has a rig
// excitation, and the methods that need one refuse the others.
TEST(ModelInputs, RefusalsWithoutATorqueInputOrARigExcitation) {
  GearRotorModel sine(params(), excitation(TorqueProfile::Kind::kConstant, 0.1));
  EXPECT_THROW(sine.setTorqueInput(0.2), InvalidInput);
  GearRotorModel held(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  EXPECT_THROW(held.setTorqueInput(NAN), InvalidInput);
  EXPECT_EQ(held.torqueInput(), 0.0);

  MeshInstant m;
  m.k_drive = 1e8;
  m.k_back = 1e7;
  m.preload_force = 100.0;
  m.drive_force = 17.7;
  const GearRotorModel constant(params(), std::make_shared<ConstantExcitation>(m));
  EXPECT_EQ(constant.rigExcitation(), nullptr);
  EXPECT_THROW(PeriodicExponentialPropagator(constant, 0.0, 1e-3), InvalidInput);
  EXPECT_THROW(integrateReduced(constant, Fidelity::kLinearModal, 0.0, State6::Zero(), 1e-3, 1e-3, nullptr), InvalidInput);
}

// The propagator keeps its own model: the caller's model changing its input or going away (what a
// rebuild does) leaves it as it was built.
TEST(ModelInputs, PropagatorOwnsItsModel) {
  auto model = std::make_unique<GearRotorModel>(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  model->setTorqueInput(0.1);
  const State6 y0 = staticEquilibrium(*model, 0.0);
  const PeriodicExponentialPropagator kept(*model, 0.0, 1e-3);
  model->setTorqueInput(0.5);
  model.reset();
  std::vector<double> a, b;
  IntegratorOptions o;
  kept.run(y0, 0.03, [&](double, const State6& y) { a.push_back(y[2]); }, o);
  ASSERT_EQ(a.size(), 31u);
  GearRotorModel again(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  again.setTorqueInput(0.1);
  PeriodicExponentialPropagator(again, 0.0, 1e-3).run(y0, 0.03, [&](double, const State6& y) { b.push_back(y[2]); }, o);
  EXPECT_EQ(a, b);
}

// The estimator's torque reaches every fidelity: after a step to 0.4 N m the quasi-static model's
// mesh force settles at T / r_p = 70.9 N (seed 000 eq 14).
TEST(ModelInputs, EstimatorTorqueReachesTheReducedFidelities) {
  for (Fidelity f : {Fidelity::kQuasiStatic, Fidelity::kLinearModal}) {
    DynamicsEstimator est(rig(), {1.2e8, 1.2e8}, 1000.0);
    est.setFidelity(f);
    est.reset(0.0, 0.1);
    est.advanceTo(0.03, nullptr);
    est.setTorque(0.4);
    double sum = 0.0;
    int n = 0;
    est.advanceTo(0.3, [&](const DynamicsSample& s) {
      if (s.t > 0.24) {
        sum += s.mesh_force;
        ++n;
      }
      EXPECT_EQ(s.torque, 0.4);
    });
    ASSERT_EQ(n, 60) << toString(f);
    EXPECT_NEAR(sum / n, 0.4 / 5.6382e-3, 0.02 * 70.9) << toString(f);
  }
}

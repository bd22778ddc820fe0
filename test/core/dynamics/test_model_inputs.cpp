// The model's inputs and ownership: the measured torque as the model's input (against seed 000
// eq 14 and against the same torque as a constant profile), the measured motion as the input of a
// model over the sliced mesh (two models over one excitation each at its own motion), the rig
// excitation known by type (refusals where there is none), and an exact propagator independent of
// the model it was built from.
#include <gtest/gtest.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/gear/sliced_mesh.hpp"
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
// with T_g = T_p r_g / r_p, docs/model.md), r_p = 5.638 mm for the seed pair (m 0.6 mm, 20 teeth,
// 20 deg).
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
  EXPECT_THROW(
      integrateReduced(constant, Fidelity::kLinearModal, 0.0, State6::Zero(), 1e-3, 1e-3, nullptr),
      InvalidInput);

  // Parameters that overflow the system matrix (a mesh damping of 1e307 N s/m over the equivalent
  // mass's 0.9 g: -Inf) are refused by name, not carried into NaN propagators or a logic error
  // (an independent review found the block-structure check throwing std::logic_error there).
  GearRotorParameters huge = params();
  huge.mesh_damping = 1e307;
  const GearRotorModel overflowing(huge, excitation(TorqueProfile::Kind::kConstant, 0.1));
  try {
    PeriodicExponentialPropagator(overflowing, 0.0, 1e-3);
    ADD_FAILURE() << "an overflowing system matrix was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("system matrix"), std::string::npos) << e.what();
  }
}

// The propagator keeps its own model: the caller's model changing its input or going away (what a
// rebuild does) leaves it as it was built.
TEST(ModelInputs, PropagatorOwnsItsModel) {
  auto model =
      std::make_unique<GearRotorModel>(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  model->setTorqueInput(0.1);
  const State6 y0 = staticEquilibrium(*model, 0.0);
  const PeriodicExponentialPropagator kept(*model, 0.0, 1e-3);
  model->setTorqueInput(0.5);
  model.reset();
  std::vector<double> a, b;
  IntegratorOptions o;
  kept.run(
      y0, 0.03, [&](double, const State6& y) { a.push_back(y[2]); }, o);
  ASSERT_EQ(a.size(), 31u);
  GearRotorModel again(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  again.setTorqueInput(0.1);
  PeriodicExponentialPropagator(again, 0.0, 1e-3)
      .run(
          y0, 0.03, [&](double, const State6& y) { b.push_back(y[2]); }, o);
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

// The measured motion is the input of the model, not a setting of the excitation it shares: two
// models over one immutable SlicedExcitation, each at its own motion and torque, see each its own
// mesh phase (phi = phi_0 + f (t - t_0), sliced_mesh.hpp), its own TE rate (e' = 2 pi f A cos 2 pi
// phi) and its own drive force (T / r_p), and the same as an excitation built with that motion
// alone.
TEST(ModelInputs, MotionInputBelongsToTheModel) {
  const auto slices = std::make_shared<const SlicedMesh>(mesh(), 64);
  const double a = 1e-6, r_p = params().pinion_base_radius;
  const auto shared = std::make_shared<const SlicedExcitation>(slices, a, 0.0, 1.0 / r_p, 0.0);
  GearRotorModel forward(params(), shared), reversed(params(), shared);
  forward.setMotionInput(MeshMotion{0.01, 0.25, 333.0});
  forward.setTorqueInput(0.4);
  reversed.setMotionInput(MeshMotion{0.0, 0.9, -100.0});
  reversed.setTorqueInput(-0.2);
  MeshInstant f, r;
  forward.meshAt(0.0112, f);   // 0.25 + 333 * 0.0012 = 0.6496 turns
  reversed.meshAt(0.0112, r);  // 0.9 - 100 * 0.0112 = -0.22 -> 0.78 turns
  EXPECT_NEAR(f.phase, 0.6496, 1e-12);
  EXPECT_NEAR(r.phase, 0.78, 1e-12);
  EXPECT_NEAR(f.te_rate, kTwoPi * 333.0 * a * std::cos(kTwoPi * 0.6496), 1e-12);
  EXPECT_NEAR(r.te_rate, kTwoPi * -100.0 * a * std::cos(kTwoPi * 0.78), 1e-12);
  EXPECT_NEAR(f.drive_force, 0.4 / r_p, 1e-9);
  EXPECT_NEAR(r.drive_force, -0.2 / r_p, 1e-9);
  // Each model's next slice boundary is along its own motion: forward past 0.6496, backward below
  // 0.78.
  const SlicedExcitation alone_f(slices, a, 0.0, 1.0 / r_p, 0.0, MeshMotion{0.01, 0.25, 333.0},
                                 0.4);
  const SlicedExcitation alone_r(slices, a, 0.0, 1.0 / r_p, 0.0, MeshMotion{0.0, 0.9, -100.0},
                                 -0.2);
  EXPECT_EQ(forward.nextSwitch(0.0112), alone_f.nextSwitch(0.0112));
  EXPECT_EQ(reversed.nextSwitch(0.0112), alone_r.nextSwitch(0.0112));
  EXPECT_GT(forward.nextSwitch(0.0112), 0.0112);
  EXPECT_LT(slices->sliceAt(0.6496 + 333.0 * (forward.nextSwitch(0.0112) - 0.0112) - 1e-9, false),
            slices->sliceAt(0.6496 + 333.0 * (forward.nextSwitch(0.0112) - 0.0112) + 1e-9, false));
  MeshInstant alone;
  alone_f.at(0.0112, alone);
  EXPECT_EQ(alone.phase, f.phase);
  EXPECT_EQ(alone.k_drive, f.k_drive);
  EXPECT_EQ(alone.drive_force, f.drive_force);
  // The shared excitation kept its own (standing, no torque): neither model wrote into it.
  shared->at(0.0112, alone);
  EXPECT_EQ(alone.phase, 0.0);
  EXPECT_EQ(alone.te_rate, 0.0);
  EXPECT_EQ(alone.drive_force, 0.0);
  // A rig model has a mesh phase of its own; a non-finite motion names its field.
  GearRotorModel rig_model(params(), excitation(TorqueProfile::Kind::kInput, 0.1));
  EXPECT_THROW(rig_model.setMotionInput(MeshMotion{0.0, 0.0, 10.0}), InvalidInput);
  try {
    forward.setMotionInput(MeshMotion{0.0, 0.0, NAN});
    ADD_FAILURE() << "a NaN mesh frequency was taken";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("mesh frequency"), std::string::npos) << e.what();
  }
  EXPECT_EQ(forward.motionInput().frequency, 333.0);  // a refusal changes nothing
}

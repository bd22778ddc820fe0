// Exact propagation at any speed (sliced_modal_propagator.hpp): checked against dopri5 at tight
// tolerance on the same sliced model (GearRotorModel over SlicedExcitation) at a constant speed,
// along a run-up whose speed changes every millisecond, through standstill and reversal, through
// the chatter of the flanks around the knees (every clipped damper a linear regime); against
// the closed-form static equilibrium when standing; its system matrix against the model's own
// Jacobian; and the slicing error against the phase table, which must fall as 1/slices^2.
#include <gtest/gtest.h>

#include <cmath>

#include <unsupported/Eigen/MatrixFunctions>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/dynamics/rig_excitation.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_interval_maps.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {
const RigConfig& rig() { return test::seedServo(); }
std::shared_ptr<const AntiBacklashMesh> mesh() {
  static const auto m = std::make_shared<const AntiBacklashMesh>(
      rig().gears, rig().anti_backlash, rig().mesh_model, rig().mesh_samples);
  return m;
}
GearRotorParameters params() { return rigRotorParameters(rig(), *mesh(), {1.2e8, 1.2e8}); }
constexpr double kTe = 1e-6;  // seed_servo.yaml: dynamics.transmission_error_amplitude [m]

/// A piece of motion: from its start, `duration` seconds at mesh frequency `f` [Hz].
struct Piece {
  double duration, f;
};

struct Harness {
  std::shared_ptr<const SlicedMesh> slices;
  std::shared_ptr<const SlicedExcitation> excitation;
  GearRotorModel model;
  SlicedModalPropagator exact;
  double drive_force;
  explicit Harness(int n, double torque = 0.1)
      : slices(std::make_shared<const SlicedMesh>(mesh(), n)),
        excitation(std::make_shared<const SlicedExcitation>(
            slices, kTe, 0.0, 1.0 / params().pinion_base_radius, 0.0)),
        model(params(), excitation),
        exact(params(), slices, kTe, 0.0),
        drive_force(torque / params().pinion_base_radius) {
    model.setTorqueInput(torque);
  }
  /// dopri5 at rtol 1e-12 through the pieces (the motion input re-anchored at each, as the node
  /// does).
  State6 reference(State6 y, double phase, const std::vector<Piece>& pieces) {
    return reference(model, y, phase, pieces);
  }
  State6 reference(GearRotorModel on, State6 y, double phase, const std::vector<Piece>& pieces) {
    IntegratorOptions o;
    o.relative_tolerance = 1e-12;
    o.absolute_tolerance = 1e-20;
    o.max_step = 2e-5;
    double t = 0.0;
    for (const Piece& p : pieces) {
      on.setMotionInput(MeshMotion{t, phase, p.f});
      y = integrate(on, IntegratorMethod::kDopri5, o, t, y, t + p.duration, p.duration, nullptr);
      phase += p.f * p.duration;
      t += p.duration;
    }
    return y;
  }
  State6 propagated(State6 y, double phase, const std::vector<Piece>& pieces) {
    for (const Piece& p : pieces)
      EXPECT_TRUE(exact.propagate(y, phase, p.f, p.duration, drive_force));
    return y;
  }
  State6 equilibrium(double phase) {
    model.setMotionInput(MeshMotion{0.0, phase, 0.0});
    return staticEquilibrium(model, 0.0);
  }
};

double relativeError(const State6& a, const State6& ref) {
  // Displacements against the largest displacement, velocities against the largest velocity.
  const double dx =
      (a.head<3>() - ref.head<3>()).cwiseAbs().maxCoeff() / ref.head<3>().cwiseAbs().maxCoeff();
  const double dv =
      (a.tail<3>() - ref.tail<3>()).cwiseAbs().maxCoeff() / ref.tail<3>().cwiseAbs().maxCoeff();
  return std::max(dx, dv);
}

double meshHz(double rpm) { return rpm / 60.0 * 20.0; }  // z_p = 20 (seed 000 Table 1)
}  // namespace

TEST(SlicedMesh, KeepsEverySwitchAndTheMeanStiffness) {
  const SlicedMesh s(mesh(), 64);
  for (double sw : mesh()->switchingPhases()) {
    bool found = false;
    for (int j = 0; j < s.size() && !found; ++j) found = std::abs(s.start(j) - sw) < 1e-12;
    EXPECT_TRUE(found) << "switching phase " << sw << " is not a slice boundary";
  }
  // The slice means integrate to the table's mean over the period (16-point midpoint per slice
  // against 4096 points of the table).
  double sliced = 0.0, table = 0.0;
  for (int j = 0; j < s.size(); ++j) sliced += (s.k1(j) + s.kChain(j)) * (s.end(j) - s.start(j));
  for (int i = 0; i < 4096; ++i) {
    const CompositeMesh c = mesh()->at((i + 0.5) / 4096.0, 0.0);
    table += (c.k1 + c.k_chain) / 4096.0;
  }
  EXPECT_NEAR(sliced / table, 1.0, 1e-4);
  EXPECT_THROW(SlicedMesh(mesh(), 2), InvalidInput);
  // linear_modal's one slice holds the library's one period mean (AntiBacklashMesh::periodMeans,
  // as meanMeshStiffness takes it), not a second mean over these slices.
  const auto mean = SlicedMesh::periodMean(mesh());
  ASSERT_EQ(mean->size(), 1);
  EXPECT_EQ(mean->k1(0), mesh()->periodMeans().k1);
  EXPECT_EQ(mean->kChain(0), mesh()->periodMeans().k_chain);
  EXPECT_EQ(mean->k1(0) + mean->kChain(0), meanMeshStiffness(*mesh()));
  EXPECT_NEAR((mean->k1(0) + mean->kChain(0)) / table, 1.0,
              1e-4);  // and the 4096-point quadrature above
}

TEST(SlicedModalPropagator, SystemMatrixIsTheModelsJacobian) {
  Harness h(64);
  const int j = 5;
  const double phase = 0.5 * (h.slices->start(j) + h.slices->end(j));
  const State6 y = h.equilibrium(phase);
  h.model.setMotionInput(MeshMotion{0.0, phase, meshHz(1000)});
  const Matrix6 jac = h.model.jacobian(0.0, y);
  // Finite differences of the model's right-hand side in the linear regime (independent of both).
  for (int c = 0; c < 6; ++c) {
    State6 dy = State6::Zero();
    dy[c] = c < 3 ? 1e-12 : 1e-8;
    State6 fp, fm;
    h.model.rhs(0.0, y + dy, fp);
    h.model.rhs(0.0, y - dy, fm);
    const State6 column = (fp - fm) / (2.0 * dy[c]);
    for (int r = 0; r < 6; ++r)
      EXPECT_NEAR(column[r], jac(r, c), 1e-6 * std::max(1.0, std::abs(jac(r, c))));
  }
}

TEST(SlicedModalPropagator, ConstantSpeedMatchesDopri5) {
  Harness h(128);
  const State6 y0 = h.equilibrium(0.1);
  const std::vector<Piece> pieces(20, Piece{1e-3, meshHz(1000)});
  const State6 ref = h.reference(y0, 0.1, pieces), got = h.propagated(y0, 0.1, pieces);
  EXPECT_LT(relativeError(got, ref), 1e-8);
  // Whole duration in one call: the same result (the step length is free).
  State6 one = y0;
  double phase = 0.1;
  ASSERT_TRUE(h.exact.propagate(one, phase, meshHz(1000), 0.02, h.drive_force));
  EXPECT_LT(relativeError(one, ref), 1e-8);
  EXPECT_NEAR(phase, 0.1 + meshHz(1000) * 0.02, 1e-9);
}

// The interval maps of a constant speed (sliced_interval_maps.hpp) are the same exact solution as a
// matrix: over each of the three 1 ms intervals of a mesh period at 1000 rpm (about 86 slices
// each) the whole map gives the slice-by-slice propagation of a loaded state to 1e-12 and dopri5's
// at rtol 1e-12 to 1e-8; a boundary's head followed by its tail is the whole map, and a stretch
// from inside the interval (exactly to the next boundary, then its tail) is the slice-by-slice
// one from there. Every piece of every interval is a slice of the sliced mesh, and the boundaries
// run from 0 to the interval's 1/3 turn.
TEST(SlicedIntervalMaps, AreTheSliceBySliceSolutionAsAMatrix) {
  Harness h(256);
  const double f = meshHz(1000);
  SlicedIntervalMaps maps(*h.slices, 3, f);
  ASSERT_EQ(maps.intervals(), 3);
  for (int i = 0; i < 3; ++i) {  // the first call for an interval makes nothing (kUsesBeforeMaking)
    State6 y = h.equilibrium(0.0);
    EXPECT_FALSE(maps.toEnd(h.exact, i, 0, y, h.drive_force));
    EXPECT_EQ(y, h.equilibrium(0.0));
  }
  EXPECT_EQ(maps.intervalsMade(), 0);
  for (int i = 0; i < 3; ++i) {
    const double q0 = i / 3.0;
    const int end = maps.boundaries(i);
    EXPECT_GT(end, 80) << i;
    EXPECT_EQ(maps.offset(i, 0), 0.0);
    EXPECT_NEAR(maps.offset(i, end), 1.0 / 3.0, 1e-15);
    const State6 y0 =
        h.equilibrium(q0) + (State6() << 1e-8, -2e-8, 3e-9, 1e-5, 2e-5, -1e-5).finished();
    State6 sliced = y0;
    double phase = q0;
    ASSERT_TRUE(h.exact.propagate(sliced, phase, f, 1e-3, h.drive_force));
    State6 whole = y0;
    ASSERT_TRUE(maps.toEnd(h.exact, i, 0, whole, h.drive_force));
    EXPECT_LT(relativeError(whole, sliced), 1e-12) << i;
    EXPECT_LT(relativeError(whole, h.reference(y0, q0, {Piece{1e-3, f}})), 1e-8) << i;
    for (int m : {1, end / 2, end - 1}) {
      State6 split = y0;
      ASSERT_TRUE(maps.fromStart(h.exact, i, m, split, h.drive_force));
      ASSERT_TRUE(maps.toEnd(h.exact, i, m, split, h.drive_force));
      EXPECT_LT(relativeError(split, whole), 1e-12) << i << " " << m;
    }
    // From 0.4 of the way through: exactly to the next boundary, then that boundary's tail.
    State6 inside = y0;
    phase = q0;
    ASSERT_TRUE(h.exact.propagate(inside, phase, f, 0.4e-3, h.drive_force));
    State6 rest = inside;
    ASSERT_TRUE(h.exact.propagate(rest, phase, f, 0.6e-3, h.drive_force));
    const int m = maps.boundaryAtOrBefore(i, f * 0.4e-3) + 1;
    double to = q0 + f * 0.4e-3;
    ASSERT_TRUE(h.exact.propagate(inside, to, f, (q0 + maps.offset(i, m) - to) / f, h.drive_force));
    ASSERT_TRUE(maps.toEnd(h.exact, i, m, inside, h.drive_force));
    EXPECT_LT(relativeError(inside, rest), 1e-12) << i;
  }
  EXPECT_EQ(maps.intervalsMade(), 3);
  // A parameter change: made again on the next use.
  maps.invalidate();
  State6 y = h.equilibrium(0.0);
  ASSERT_FALSE(maps.toEnd(h.exact, 0, 0, y, h.drive_force));
  ASSERT_TRUE(maps.toEnd(h.exact, 0, 0, y, h.drive_force));
  EXPECT_EQ(maps.intervalsMade(), 4);
  EXPECT_THROW(SlicedIntervalMaps(*h.slices, 0, f), InvalidInput);
  EXPECT_THROW(SlicedIntervalMaps(*h.slices, 3, -f), InvalidInput);
}

TEST(SlicedModalPropagator, RunUpWithTheSpeedChangingEveryMillisecond) {
  // 0 -> 6000 rpm in 50 ms (a violent run-up: 12,600 rad/s^2), a new speed every millisecond.
  Harness h(128);
  std::vector<Piece> pieces;
  for (int k = 0; k < 50; ++k) pieces.push_back({1e-3, meshHz(6000.0 * (k + 0.5) / 50.0)});
  const State6 y0 = h.equilibrium(0.3);
  EXPECT_LT(relativeError(h.propagated(y0, 0.3, pieces), h.reference(y0, 0.3, pieces)), 1e-8);
}

TEST(SlicedModalPropagator, ThroughStandstillAndReversal) {
  // +1000 rpm down through 0 to -1000 rpm and back, pieces of 0.7 ms (not a divisor of anything).
  Harness h(128);
  std::vector<Piece> pieces;
  for (int k = 0; k <= 40; ++k)
    pieces.push_back({7e-4, meshHz(1000.0 * std::cos(kTwoPi * k / 40.0))});
  pieces.push_back({2e-3, 0.0});  // standing still
  for (int k = 0; k <= 20; ++k) pieces.push_back({7e-4, -meshHz(500.0 * k / 20.0)});
  const State6 y0 = h.equilibrium(0.9);
  EXPECT_LT(relativeError(h.propagated(y0, 0.9, pieces), h.reference(y0, 0.9, pieces)), 1e-8);
}

TEST(SlicedModalPropagator, OneFlankAboveTheKneeAndPastTheReverseKnee) {
  // The anti-backlash gear far above its knee (the back path lifted: the seed rig's knee is at a
  // pinion torque of 6.95 N*m, docs/calibration.md section 5) and past its reverse knee (-0.55 N*m:
  // the drive flank lifted): each is linear with its own stiffness, damping share and the preload
  // force as a constant, so the exact propagation holds there too (no dopri5), through a run-up and
  // at standstill. 20 N*m, not 10: at 10 N*m the transients at the tooth switches during this
  // run-up briefly reload the back path (dopri5 shows the flank force dipping from 1773 N to 957
  // N), a real change of regime that the propagation rightly hands back.
  for (double torque : {20.0, -1.0}) {
    Harness h(128, torque);
    std::vector<Piece> pieces;
    for (int k = 0; k < 20; ++k) pieces.push_back({1e-3, meshHz(1000.0 * (k + 0.5) / 20.0)});
    pieces.push_back({2e-3, 0.0});
    const State6 y0 = h.equilibrium(0.1);
    const double delta = y0[2] + y0[0] - y0[1] - kTe * std::sin(kTwoPi * 0.1);
    const double fp = mesh()->preloadForce(), kc = h.slices->kChain(h.slices->sliceAt(0.1, false));
    if (torque > 0.0) {
      EXPECT_LT(fp - kc * delta, 0.0) << "the back path should be lifted at " << torque << " N*m";
    } else {
      EXPECT_LT(fp + h.slices->k1(h.slices->sliceAt(0.1, false)) * delta, 0.0)
          << "the drive flank should be lifted";
    }
    EXPECT_LT(relativeError(h.propagated(y0, 0.1, pieces), h.reference(y0, 0.1, pieces)), 1e-8)
        << torque << " N*m";
  }
}

/// Along dopri5 on the model (rtol 1e-12) from y0 at mesh frequency f, every `dt` [s] for
/// `duration`, the samples where a closed flank's damper is clipped, from the model's own forces
/// alone (GearRotorModel::forces, which shares no code with the propagator): the mesh slope
/// dF/d(delta) is the sum of the closed flanks' stiffnesses unless a damper clips, at zero force
/// (that flank's slope 0: `low`) or at twice the spring force (2 k: `high`).
struct Clipped {
  int low = 0, high = 0;
};
Clipped clippedAlong(GearRotorModel model, State6 y, double phase, double f, double duration,
                     double dt) {
  model.setMotionInput(MeshMotion{0.0, phase, f});
  IntegratorOptions o;
  o.relative_tolerance = 1e-12;
  o.absolute_tolerance = 1e-20;
  o.max_step = dt;
  Clipped out;
  integrate(
      model, IntegratorMethod::kDopri5, o, 0.0, y, duration, dt, [&](double t, const State6& z) {
        const GearRotorForces forces = model.forces(t, z);
        MeshInstant m;
        model.meshAt(t, m);
        const double closed =
            (forces.regime.code[0] ? m.k_drive : 0.0) + (forces.regime.code[1] ? m.k_back : 0.0);
        if (forces.mesh_slope < closed * (1.0 - 1e-9)) ++out.low;
        if (forces.mesh_slope > closed * (1.0 + 1e-9)) ++out.high;
      });
  return out;
}

// propagateMeasured through a flank that lifts and lands every mesh period (torques around the
// anti-backlash knee, ~6-7 N m on the seed rig), in 1 ms calls as the node's 1 kHz output grid
// makes them. Each lift clips the damper of the opening flank at zero force for a moment, and each
// landing clips the landing flank's at twice its spring force (the Modelica ElastoBacklash rule of
// GearRotorModel): both are linear regimes of their own (sliced_modal_propagator.hpp, FlankState),
// so the whole run is propagated exactly, no dopri5 stretch at all, and agrees with dopri5 at rtol
// 1e-12 through the same 20 ms to 1e-8 (a dopri5 stretch for every clipped moment would cost about
// 30 us each, and the stretches' rtol 1e-8 would bound the agreement here at 1e-6).
TEST(SlicedModalPropagator, ChatterAroundTheKneeIsPropagatedExactly) {
  long stretches = 0, changes = 0;
  Clipped clipped;
  for (double torque : {5.5, 6.0, 6.5, 7.0}) {
    Harness h(128, torque);
    const double f = meshHz(1000), interval = 1e-3;
    const State6 y0 = h.equilibrium(0.1);
    State6 y = y0;
    double phase = 0.1;
    const auto dopri5 = [&](double, double, State6&, double&) {
      ++stretches;
    };  // counted: none expected
    std::vector<Piece> pieces;
    for (int k = 0; k < 20; ++k) {
      propagateMeasured(h.exact, y, phase, f, k * interval, (k + 1) * interval, h.drive_force,
                        dopri5);
      pieces.push_back({interval, f});
      ASSERT_TRUE(y.allFinite());
    }
    changes += h.exact.regimeChanges();
    const State6 ref = h.reference(y0, 0.1, pieces);
    EXPECT_LT(relativeError(y, ref), 1e-8) << "torque " << torque;
    const Clipped c = clippedAlong(h.model, y0, 0.1, f, 20e-3, 5e-7);
    clipped.low += c.low;
    clipped.high += c.high;
  }
  // The same at 120 rpm in 0.2 ms calls (5 kHz encoder readings, the load_sweep bag's rig): a
  // slice lasts 98 us there, and every lift and landing is located inside one. 5.25 and 5.45 N m
  // are where locateChange's false position, trying lengths of 1e-19 s right after a landing,
  // read the rounding of the contact force as a lift (5e-6 and 1.1e-5 off dopri5 before the guard
  // kRoundingValue).
  for (double torque : {5.25, 5.45}) {
    Harness h(256, torque);
    const double f = meshHz(120), interval = 2e-4;
    const State6 y0 = h.equilibrium(0.1);
    State6 y = y0;
    double phase = 0.1;
    const auto dopri5 = [&](double, double, State6&, double&) { ++stretches; };
    // Compared at every call's end: a misplaced landing shows for a few samples and then decays.
    IntegratorOptions o;
    o.relative_tolerance = 1e-12;
    o.absolute_tolerance = 1e-20;
    o.max_step = 2e-6;
    h.model.setMotionInput(MeshMotion{0.0, 0.1, f});
    State6 r = y0;
    double worst = 0.0, largest = 0.0;
    for (int k = 0; k < 500; ++k) {
      propagateMeasured(h.exact, y, phase, f, k * interval, (k + 1) * interval, h.drive_force,
                        dopri5);
      r = integrate(h.model, IntegratorMethod::kDopri5, o, k * interval, r, (k + 1) * interval,
                    interval, nullptr);
      worst = std::max(worst, std::abs((y[2] + y[0] - y[1]) - (r[2] + r[0] - r[1])));
      largest = std::max(largest, std::abs(r[2] + r[0] - r[1]));
    }
    changes += h.exact.regimeChanges();
    EXPECT_LT(worst, 1e-8 * largest) << "torque " << torque << " at 120 rpm";
  }
  std::printf(
      "contact changes located: %ld; dopri5 samples every 0.5 us with a damper clipped: %d at "
      "zero, %d at twice the spring\n",
      changes, clipped.low, clipped.high);
  EXPECT_EQ(stretches, 0);
  // The test reaches what it is about: both clipped states occur along the reference.
  EXPECT_GT(clipped.low, 0);
  EXPECT_GT(clipped.high, 0);
  EXPECT_GT(changes, 0);
}

// From equilibrium at 1 N*m (both flanks loaded) the drive force jumps to 10 N*m, above the seed
// rig's knee of 6.95 N*m (docs/calibration.md section 5): the back path lifts within the advance,
// its damper clipped at zero force as it opens. Each change is located on the exact solution and
// the propagation goes on in the regime the state is in, through the whole advance, with no hand
// back; checked against dopri5 at rtol 1e-12 on the same model.
TEST(SlicedModalPropagator, AFlankThatLiftsInsideAnAdvanceIsLocatedAndGoneThrough) {
  Harness h(128, 1.0);
  GearRotorModel lifted = h.model;
  lifted.setTorqueInput(10.0);
  const double force = 10.0 / params().pinion_base_radius, f = meshHz(1000), duration = 2e-3;
  const State6 y0 = h.equilibrium(0.3);
  State6 y = y0;
  double phase = 0.3;
  EXPECT_EQ(h.exact.propagateLinear(y, phase, f, duration, force), duration);
  EXPECT_GT(h.exact.regimeChanges(), 0) << "the back path's lift was not seen";
  const Clipped c = clippedAlong(lifted, y0, 0.3, f, duration, 1e-7);
  EXPECT_GT(c.low, 0)
      << "no damper clipped at zero: the test does not reach the opening flank's clipped moment";
  std::printf(
      "regime changes located: %ld; dopri5 samples with a damper clipped: %d at zero, %d at twice "
      "the spring\n",
      h.exact.regimeChanges(), c.low, c.high);
  const State6 ref = h.reference(lifted, y0, 0.3, {Piece{duration, f}});
  EXPECT_LT(relativeError(y, ref), 1e-8);
  // Independent: at the end the back path is lifted in the reference (s2 = F_p - k_c delta < 0).
  const double delta = ref[2] + ref[0] - ref[1] - kTe * std::sin(kTwoPi * (0.3 + f * duration));
  EXPECT_LT(
      mesh()->preloadForce() -
          h.slices->kChain(h.slices->sliceAt(std::fmod(0.3 + f * duration, 1.0), false)) * delta,
      0.0);
  // propagate, all or nothing, takes the same advance whole and gives the same bits.
  Harness again(128, 1.0);
  State6 z = y0;
  double p = 0.3;
  EXPECT_TRUE(again.exact.propagate(z, p, f, duration, force));
  EXPECT_EQ(z, y);
  EXPECT_EQ(p, phase);
}

// An ordinary gear (no anti-backlash spring) with 20 um of backlash, its mesh started 3 um back
// from its loaded place, off the drive flank: it flies free in the backlash (both flanks unloaded,
// no mesh stiffness, a free mass whose double zero eigenvalue has no eigenbasis), which the exact
// propagation hands back, and propagateMeasured's dopri5 stretches carry it until the drive flank
// lands again; the landing (through the stiffened moment) and what follows are exact again. Checked
// against dopri5 at rtol 1e-12 on the same model.
TEST(SlicedModalPropagator, FreeFlightInTheBacklashGoesToDopri5StretchesUntilAFlankLands) {
  RigConfig ordinary = rig();
  ordinary.anti_backlash.spring_stiffness = 0.0;
  ordinary.anti_backlash.preload_torque = 0.0;
  const auto plain = std::make_shared<const AntiBacklashMesh>(
      ordinary.gears, ordinary.anti_backlash, ordinary.mesh_model, ordinary.mesh_samples);
  const GearRotorParameters p = rigRotorParameters(ordinary, *plain, {1.2e8, 1.2e8});
  const double backlash = 20e-6, torque = 1.0, force = torque / p.pinion_base_radius,
               f = meshHz(1000);
  const auto slices = std::make_shared<const SlicedMesh>(plain, 128);
  ASSERT_FALSE(slices->antiBacklash());
  const auto excitation = std::make_shared<const SlicedExcitation>(slices, kTe, backlash,
                                                                   1.0 / p.pinion_base_radius, 0.0);
  GearRotorModel model(p, excitation);
  model.setTorqueInput(torque);
  const SlicedModalPropagator exact(p, slices, kTe, backlash);
  model.setMotionInput(MeshMotion{0.0, 0.2, 0.0});
  State6 y0 = staticEquilibrium(model, 0.0);
  y0[2] -= 3e-6;  // the mesh coordinate 3 um back: off the drive flank (1.3 um loaded), in the gap
  IntegratorOptions o;
  o.relative_tolerance = 1e-12;
  o.absolute_tolerance = 1e-20;
  o.max_step = 1e-6;
  long stretches = 0;
  double stretched = 0.0;  // [s] of rig time
  GearRotorModel on = model;
  const auto dopri5 = [&](double t0, double t1, State6& z, double& phase) {
    on.setMotionInput(MeshMotion{t0, phase, f});
    z = integrate(on, IntegratorMethod::kDopri5, o, t0, z, t1, t1 - t0, nullptr);
    phase += f * (t1 - t0);
    ++stretches;
    stretched += t1 - t0;
  };
  // All or nothing: propagate refuses a start in free flight and leaves the state and phase.
  State6 untouched = y0;
  double p0 = 0.2;
  EXPECT_FALSE(exact.propagate(untouched, p0, f, 1e-3, force));
  EXPECT_EQ(untouched, y0);
  EXPECT_EQ(p0, 0.2);
  State6 y = y0;
  double phase = 0.2;
  for (int k = 0; k < 4; ++k)
    propagateMeasured(exact, y, phase, f, k * 1e-3, (k + 1) * 1e-3, force, dopri5);
  model.setMotionInput(MeshMotion{0.0, 0.2, f});
  const State6 ref = integrate(model, IntegratorMethod::kDopri5, o, 0.0, y0, 4e-3, 4e-3, nullptr);
  std::printf("dopri5 stretches: %ld over %.3g us, contact changes located: %ld\n", stretches,
              stretched * 1e6, exact.regimeChanges());
  EXPECT_GT(stretches, 0) << "the free flight should be handed to dopri5";
  // Independent: the free flight's length along the reference (both flanks open: 0.1 us samples),
  // which the stretches must cover, doubling, by less than twice; the rest of the 4 ms is the
  // exact propagation's.
  double flight = 0.0;
  model.setMotionInput(MeshMotion{0.0, 0.2, f});
  integrate(model, IntegratorMethod::kDopri5, o, 0.0, y0, 4e-3, 1e-7,
            [&](double t, const State6& z) {
              const GearRotorForces g = model.forces(t, z);
              if (g.regime.code[0] == 0 && g.regime.code[1] == 0) flight += 1e-7;
            });
  std::printf("free flight along the reference: %.3g us\n", flight * 1e6);
  EXPECT_GE(stretched, flight - 2e-7);
  EXPECT_LT(stretched, 2.0 * flight + 2.0 * exact.fastestPeriodBound())
      << "the exact propagation should resume after the landing";
  EXPECT_GT(exact.regimeChanges(), 0) << "the landing should be located on the exact solution";
  EXPECT_LT(relativeError(y, ref), 1e-7);
  // Independent: along the reference the mesh does fly free (both flanks open) for a while.
  int free_samples = 0;
  model.setMotionInput(MeshMotion{0.0, 0.2, f});
  integrate(model, IntegratorMethod::kDopri5, o, 0.0, y0, 4e-3, 1e-6,
            [&](double t, const State6& z) {
              const GearRotorForces g = model.forces(t, z);
              free_samples += g.regime.code[0] == 0 && g.regime.code[1] == 0;
            });
  EXPECT_GT(free_samples, 0);
}

// A state recorded from the node's replay of the 48 s load_sweep bag (docs/calibration.md section
// 7), 13.2498 s into it: 5.33 N m at 120 rpm, 211 us to the next output sample, across the tooth
// switch at phase 0 where the back path lands (parameters and state as the estimator held them).
// Within one 1.9 us step the state leaves the both-flank regime, comes back and leaves again; a
// search over the whole step converges on the second change, 1e-6 of the deflection off dopri5
// (rtol 1e-13, steps <= 0.1 us, which honours the tooth switch); locateChange's samples find the
// first. Stretches of dopri5 through every clipped damper, instead, miss a landing 0.43 s later
// by 2.8e-4 of that sample's TE.
TEST(SlicedModalPropagator, ALeaveAndReturnInsideAStepIsTakenAtTheFirstChange) {
  GearRotorParameters p =
      rigRotorParameters(rig(), *mesh(), {108737127.15110265, 108737127.15110265});
  p.bearing_damping = {76.85441266998204, 91.64052490101723};
  p.mesh_damping = 33.898072824498264;
  const auto slices = std::make_shared<const SlicedMesh>(mesh(), 256);
  const auto excitation =
      std::make_shared<const SlicedExcitation>(slices, kTe, 0.0, 1.0 / p.pinion_base_radius, 0.0);
  const double torque = 5.3310678105797678, f = 39.999999999999993, phase = 0.99219894409179688;
  const double duration = 13.25 - 13.249789270999999;
  const State6 y0 =
      (State6() << -8.691466041753754e-06, 8.6978623985479104e-06, 2.786766491654544e-05,
       0.00043240893594604073, 0.00062322605655164547, 4.540223838771229e-06)
          .finished();
  const SlicedModalPropagator exact(p, slices, kTe, 0.0);
  State6 y = y0;
  double ph = phase;
  ASSERT_EQ(exact.propagateLinear(y, ph, f, duration, torque / p.pinion_base_radius), duration);
  GearRotorModel model(p, excitation);
  model.setTorqueInput(torque);
  model.setMotionInput(MeshMotion{0.0, phase, f});
  IntegratorOptions o;
  o.relative_tolerance = 1e-13;
  o.absolute_tolerance = 1e-21;
  o.max_step = 1e-7;
  const State6 ref =
      integrate(model, IntegratorMethod::kDopri5, o, 0.0, y0, duration, duration, nullptr);
  const double delta = y[2] + y[0] - y[1], delta_ref = ref[2] + ref[0] - ref[1];
  std::printf("contact changes: %ld, deflection %.10e against dopri5's %.10e\n",
              exact.regimeChanges(), delta, delta_ref);
  EXPECT_GE(exact.regimeChanges(), 5);
  EXPECT_LT(std::abs(delta - delta_ref), 1e-8 * std::abs(delta_ref));
}

TEST(SlicedModalPropagator, StandingStillSettlesOnTheClosedFormEquilibrium) {
  // At f = 0 the model is LTI with constant forcing: y(inf) = static equilibrium at that phase,
  // whatever the start (here displaced by 0.2 um and moving). A 1 um push, as this test had, clips
  // a flank's damper in the first 10 us (the drive flank's force swings from 246 N to 29 N,
  // dopri5), which the exact propagation now sees inside its step and hands back.
  Harness h(64);
  const double phase = 0.37;
  const State6 eq = h.equilibrium(phase);
  State6 y = eq;
  y[0] += 2e-7;
  y[5] += 1e-4;
  double p = phase;
  ASSERT_TRUE(h.exact.propagate(y, p, 0.0, 0.5, h.drive_force));
  EXPECT_EQ(p, phase);
  EXPECT_LT((y.head<3>() - eq.head<3>()).cwiseAbs().maxCoeff(),
            1e-10 * eq.head<3>().cwiseAbs().maxCoeff());
}

TEST(SlicedModalPropagator, AContactChangeInsideAStepIsSeen) {
  // Standing, pushed by 1 um and moving: the transient clips a flank's damper within the first
  // 10 us and has died out long before the step's end, where the contacts look as they began. The
  // check at the ends alone accepted this 0.5 s step whole in the both-flank law; the bound over
  // the step (regimeMargin) must cut it so that the changes are seen and located. Independent
  // evidence that the contacts do leave that law: along dopri5's trajectory the model's mesh force
  // departs from (k1 + k_c) delta + c delta'. The state 20 us on, past the clipped moment, must
  // match dopri5's, which the both-flank law alone misses by far more.
  Harness h(64);
  const double phase = 0.37;
  State6 y = h.equilibrium(phase);
  y[0] += 1e-6;
  y[5] += 1e-3;
  IntegratorOptions o;
  o.relative_tolerance = 1e-12;
  o.absolute_tolerance = 1e-20;
  o.max_step = 1e-7;
  State6 r = y;
  double worst = 0.0;
  h.model.setMotionInput(MeshMotion{0.0, phase, 0.0});
  for (int i = 0; i < 200; ++i) {
    r = integrate(h.model, IntegratorMethod::kDopri5, o, i * 1e-7, r, (i + 1) * 1e-7, 1e-7,
                  nullptr);
    const GearRotorForces f = h.model.forces((i + 1) * 1e-7, r);
    const int j = h.slices->sliceAt(phase, false);
    const double linear =
        (h.slices->k1(j) + h.slices->kChain(j)) * f.delta + params().mesh_damping * f.delta_rate;
    worst = std::max(worst, std::abs(f.mesh - linear));
  }
  EXPECT_GT(worst, 1.0)
      << "the push should clip a damper (a mesh force off the linear law by more than 1 N)";
  State6 z = y;
  double p = phase;
  ASSERT_TRUE(h.exact.propagate(z, p, 0.0, 2e-5, h.drive_force));
  EXPECT_GT(h.exact.checkedSubsteps(), 0);
  EXPECT_GT(h.exact.regimeChanges(), 0);
  EXPECT_LT(relativeError(z, r), 1e-8);
  // The both-flank law through the same 20 us (the model with its clipping rule taken away: a
  // linear ODE, dopri5): far from the reference, so the comparison above can fail.
  const int j = h.slices->sliceAt(phase, false);
  Matrix6 a = Matrix6::Zero();
  a.topRightCorner<3, 3>().setIdentity();
  const Eigen::Vector3d m_inv(1.0 / params().pinion_mass, 1.0 / params().gear_mass,
                              1.0 / params().equivalentMass());
  a.bottomLeftCorner<3, 3>() =
      -(m_inv.asDiagonal() *
        meshBearingMatrix(h.slices->k1(j) + h.slices->kChain(j), params().bearing_stiffness));
  a.bottomRightCorner<3, 3>() =
      -(m_inv.asDiagonal() * meshBearingMatrix(params().mesh_damping, params().bearing_damping));
  const State6 eq = h.equilibrium(phase);
  const State6 unclipped = eq + (a * 2e-5).exp() * (y - eq);
  EXPECT_GT(relativeError(unclipped, r), 1e-4);
  // And the whole 0.5 s, on to rest.
  p = phase;
  ASSERT_TRUE(h.exact.propagate(y, p, 0.0, 0.5, h.drive_force));
  EXPECT_LT((y.head<3>() - eq.head<3>()).cwiseAbs().maxCoeff(),
            1e-10 * eq.head<3>().cwiseAbs().maxCoeff());
}

TEST(SlicedModalPropagator, SlicingErrorAgainstThePhaseTableFallsWithTheSliceCount) {
  // Fixed speed 1000 rpm, 30 ms from equilibrium: the sliced model against the table model
  // (RigExcitation, dopri5 both), on the displacements (the TE is one). Pointwise the staircase
  // differs from the table by up to half a slice's stiffness change (first order in the slice
  // width); a slice rate near the mesh mode (~56 kHz: 128 slices at 333 Hz) rings it up, so the
  // fall is not a clean power law. Measured (docs/model.md): 2.7e-4 (64), 1.9e-4 (128),
  // 8.1e-6 (256), 1.0e-6 (512).
  RigExcitationSpec spec;
  spec.speed = 1000.0 * kTwoPi / 60.0;
  spec.te_amplitude = kTe;
  spec.balanced_load = true;
  spec.torque.mean = 0.1;
  const GearRotorModel table(params(), std::make_shared<RigExcitation>(mesh(), params(), spec));
  IntegratorOptions o;
  o.relative_tolerance = 1e-12;
  o.absolute_tolerance = 1e-20;
  o.max_step = 2e-5;
  const State6 y0 = staticEquilibrium(table, 0.0);
  const State6 ref = integrate(table, IntegratorMethod::kDopri5, o, 0.0, y0, 0.03, 0.03, nullptr);
  std::vector<double> errors;
  for (int n : {128, 256, 512}) {
    Harness h(n);
    State6 y = y0;
    double phase = 0.0;
    ASSERT_TRUE(h.exact.propagate(y, phase, meshHz(1000), 0.03, h.drive_force));
    errors.push_back((y.head<3>() - ref.head<3>()).cwiseAbs().maxCoeff() /
                     ref.head<3>().cwiseAbs().maxCoeff());
    std::printf("slices %d: displacement error against the phase table %.3g\n", n, errors.back());
  }
  EXPECT_GT(errors[0] / errors[1], 4.0);
  EXPECT_GT(errors[1] / errors[2], 4.0);
  EXPECT_LT(errors[1], 2e-5);
  EXPECT_LT(errors[2], 3e-6);
}

// The slices' modes come from Newton on the closed-form characteristic polynomial, seeded by a
// neighbouring slice (sliced_modal_propagator.cpp, decomposeSeeded). Checked against what shares
// no code with it: the product over the slices of the matrix exponentials of the model's own
// Jacobian (GearRotorModel::jacobian, Eigen's Pade-based MatrixFunctions), i.e. the monodromy
// matrix of the sliced model at a constant speed.
TEST(SlicedModalPropagator, SeededModesGiveTheMonodromyOfTheJacobians) {
  Harness h(256);
  const double f = meshHz(1000);
  const Matrix6 fast = h.exact.monodromy(f);
  // One slice made by the general eigensolver (no seed yet), every other one seeded.
  EXPECT_EQ(h.exact.decompositions(), h.slices->size());
  EXPECT_EQ(h.exact.generalDecompositions(), 1);
  Matrix6 reference = Matrix6::Identity();
  for (int j = 0; j < h.slices->size(); ++j) {
    const double mid = 0.5 * (h.slices->start(j) + h.slices->end(j));
    const State6 y = h.equilibrium(mid);
    h.model.setMotionInput(MeshMotion{0.0, mid, f});
    const Matrix6 a = h.model.jacobian(0.0, y);
    // In balanced units (velocities over omega_ref = 1e5 rad/s) the Pade approximant is accurate;
    // on A as it is, whose blocks span ten decades, it loses five digits.
    Eigen::Matrix<double, 6, 1> d;
    d << 1.0, 1.0, 1.0, 1e5, 1e5, 1e5;
    const Matrix6 a_b = d.cwiseInverse().asDiagonal() * a * d.asDiagonal();
    const Matrix6 step = d.asDiagonal() *
                         Matrix6((a_b * ((h.slices->end(j) - h.slices->start(j)) / f)).exp()) *
                         d.cwiseInverse().asDiagonal();
    reference = step * reference;
  }
  // Compared in the same balanced units (measured: 1e-13 of the largest entry).
  Eigen::Matrix<double, 6, 1> d;
  d << 1.0, 1.0, 1.0, 1e5, 1e5, 1e5;
  const Matrix6 diff = d.cwiseInverse().asDiagonal() * (fast - reference) * d.asDiagonal();
  const Matrix6 ref_b = d.cwiseInverse().asDiagonal() * reference * d.asDiagonal();
  EXPECT_LT(diff.cwiseAbs().maxCoeff(), 1e-11 * ref_b.cwiseAbs().maxCoeff());
}

// Above the anti-backlash knee the back path is lifted and the drive flank alone carries the
// mesh: the period map that gives the Floquet margin must be that regime's. Checked as above
// against the product of the Pade exponentials of the model's own Jacobian at states in that
// regime (GearRotorModel::forces decides the contacts there, sharing no code with the propagator's
// regime test), and shown to differ from the both-flank map it replaced.
TEST(SlicedModalPropagator, MonodromyIsTheRegimeTheStateIsIn) {
  const double torque =
      20.0;  // N*m: well above the seed rig's knee of 6.95 N*m (docs/calibration.md section 5)
  Harness h(256, torque);
  const double f = meshHz(1000);
  Eigen::Matrix<double, 6, 1> d;  // balanced units, as above
  d << 1.0, 1.0, 1.0, 1e5, 1e5, 1e5;
  Matrix6 reference = Matrix6::Identity();
  for (int j = 0; j < h.slices->size(); ++j) {
    const double mid = 0.5 * (h.slices->start(j) + h.slices->end(j));
    const State6 y = h.equilibrium(mid);
    h.model.setMotionInput(MeshMotion{0.0, mid, f});
    ASSERT_EQ(h.model.forces(0.0, y).regime.code[1], 0)
        << "the back path should be lifted at slice " << j;
    const Matrix6 a_b = d.cwiseInverse().asDiagonal() * h.model.jacobian(0.0, y) * d.asDiagonal();
    reference = d.asDiagonal() *
                Matrix6((a_b * ((h.slices->end(j) - h.slices->start(j)) / f)).exp()) *
                d.cwiseInverse().asDiagonal() * reference;
  }
  const std::optional<Matrix6> fast = h.exact.monodromy(f, h.equilibrium(0.1), 0.1);
  ASSERT_TRUE(fast.has_value());
  const auto balanced = [&](const Matrix6& m) {
    return Matrix6(d.cwiseInverse().asDiagonal() * m * d.asDiagonal());
  };
  const double scale = balanced(reference).cwiseAbs().maxCoeff();
  EXPECT_LT((balanced(*fast) - balanced(reference)).cwiseAbs().maxCoeff(), 1e-11 * scale);
  // The both-flank map (the mesh about twice as stiff) is a different motion.
  EXPECT_GT((balanced(h.exact.monodromy(f)) - balanced(reference)).cwiseAbs().maxCoeff(),
            1e-3 * scale);
  // A state in no linear regime has no period map: the mesh closing so fast that the drive
  // flank's damper force would exceed its spring force (clipped: |F_d| <= F_s, the regime rule).
  State6 slamming = h.equilibrium(0.1);
  slamming[5] += 1e3;  // m/s along the line of action
  h.model.setMotionInput(MeshMotion{0.0, 0.1, f});
  ASSERT_EQ(h.model.forces(0.0, slamming).regime.code[1], 0);
  EXPECT_FALSE(h.exact.monodromy(f, slamming, 0.1).has_value());
  // Nor a back path still closed whose damper is clipped at zero as it opens (no force, as if
  // lifted, but not a lift that lasts a period): at 6 N*m, just below the knee, both flanks loaded
  // at rest, then the mesh opening at a rate between s2 / c2 (the back path's damper would pull)
  // and s1 / c1 (the drive flank's stays below twice its spring). GearRotorModel::forces decides
  // the contacts: the back path closed with no force, the drive flank loaded unclipped.
  Harness near(256, 6.0);
  State6 opening = near.equilibrium(0.1);
  ASSERT_TRUE(near.exact.monodromy(f, opening, 0.1).has_value()) << "both flanks loaded at rest";
  near.model.setMotionInput(MeshMotion{0.0, 0.1, f});
  const GearRotorForces at_rest = near.model.forces(0.0, opening);
  MeshInstant m;
  near.model.meshAt(0.0, m);
  const double c1 = params().mesh_damping * m.k_drive / (m.k_drive + m.k_back),
               c2 = params().mesh_damping - c1;
  const double s1 = mesh()->preloadForce() + m.k_drive * at_rest.delta,
               s2 = mesh()->preloadForce() - m.k_back * at_rest.delta;
  ASSERT_LT(s2 / c2, s1 / c1) << "no opening rate clips the back path's damper alone";
  opening[5] += 0.5 * (s2 / c2 + s1 / c1);  // delta' up by this much: the mesh opening
  const GearRotorForces clipped = near.model.forces(0.0, opening);
  ASSERT_EQ(clipped.regime.code[1], 1) << "the back path should still be closed";
  ASSERT_EQ(clipped.back_flank, 0.0) << "its damper should be clipped at zero";
  ASSERT_GT(clipped.drive_flank, 0.0);
  ASSERT_LT(clipped.drive_flank, 2.0 * s1) << "the drive flank's damper should not be clipped";
  EXPECT_FALSE(near.exact.monodromy(f, opening, 0.1).has_value());
}

TEST(SlicedModalPropagator, APhaseJustBelowAWholeTurnIsThePeriodsFirstSlice) {
  // phase - floor(phase) rounds to 1.0 for a phase of -1e-17; the regime of the state must then be
  // judged on the period's first slice, where the mesh is (phase 0), not on its last (sliceAt
  // clamps 1.0 to it). Across the tooth switch the drive flank's stiffness jumps and with it the
  // share of the mesh damping each path carries (c1 = c_m k_drive / (k_drive + k_back)), so a mesh
  // opening at a rate between the two slices' clipping rates is in a linear regime on one and in
  // none on the other (the damper rule of MonodromyIsTheRegimeTheStateIsIn above): the answer at
  // -1e-17 must be the one at phase 0, matrix for matrix.
  const double f = meshHz(1000);
  ASSERT_EQ(-1e-17 - std::floor(-1e-17), 1.0) << "the rounding this test is about";
  Harness h(256, 3.0);
  const State6 rest = h.equilibrium(0.0);
  int differing = 0;
  for (double rate = 1e-4; rate < 1e3; rate *= 1.02) {  // [m/s] the mesh deflection's rate
    State6 y = rest;
    y[5] += rate;
    const std::optional<Matrix6> at_zero = h.exact.monodromy(f, y, 0.0);
    const std::optional<Matrix6> just_below = h.exact.monodromy(f, y, -1e-17);
    ASSERT_EQ(at_zero.has_value(), just_below.has_value()) << "at " << rate << " m/s";
    if (at_zero) {
      EXPECT_EQ(*at_zero, *just_below) << "at " << rate << " m/s";
    }
    // Where the last slice judges the state apart from the first, the two answers differ.
    const std::optional<Matrix6> last = h.exact.monodromy(f, y, 1.0 - 1e-9);
    differing += last.has_value() != at_zero.has_value() || (last && *last != *at_zero);
  }
  EXPECT_GT(differing, 0) << "no rate at which the first and the last slice judge the state apart";
}

TEST(SlicedModalPropagator, ABearingChangeIsReseededAndStaysExact) {
  // After a bearing-stiffness change every slice is decomposed again as it is crossed, seeded by
  // the slice behind it: no general eigensolver at all, and still dopri5's answer. A change by a
  // factor of 100 moves the modes far from every seed: whatever the seeded solve then accepts or
  // refuses (to the general solver), the result must still be dopri5's.
  for (double factor : {1.1, 100.0}) {
    Harness h(128);
    State6 y = h.equilibrium(0.2);
    double phase = 0.2;
    ASSERT_TRUE(
        h.exact.propagate(y, phase, meshHz(1000), 4e-3, h.drive_force));  // every slice decomposed
    GearRotorParameters changed = params();
    changed.bearing_stiffness = {1.2e8 * factor, 1.3e8 * factor};
    h.exact.setParameters(changed);
    GearRotorModel stiffer(changed, h.excitation);
    stiffer.setTorqueInput(h.model.torqueInput());
    stiffer.setMotionInput(MeshMotion{0.0, 0.2, 0.0});
    const State6 y0 = staticEquilibrium(stiffer, 0.0);
    const long general = h.exact.generalDecompositions();
    const std::vector<Piece> pieces(8, Piece{1e-3, meshHz(1500)});
    const State6 got = h.propagated(y0, 0.2, pieces), ref = h.reference(stiffer, y0, 0.2, pieces);
    EXPECT_LT(relativeError(got, ref), 1e-8) << "factor " << factor;
    if (factor < 2.0) {
      EXPECT_EQ(h.exact.generalDecompositions(), general)
          << "a 10 % change needed the general solver";
    }
    std::printf("bearing stiffness x%g: %ld of %ld decompositions by the general solver\n", factor,
                h.exact.generalDecompositions() - general, h.exact.decompositions());
  }
}

TEST(SlicedModalPropagator, AMeshDampingChangeRemakesTheContactRules) {
  // The contact rules and the mesh terms of every regime are tabulated per slice, and only a new
  // mesh damping changes them (a bearing change keeps them: the test above). With the TE forcing's
  // damper term (-c A w cos theta) and the rules' damper coefficients read from those tables, rules
  // kept from the old damping put the forcing off by about 0.6 % of the mesh force here; the
  // result must be dopri5's on the new model, above the knee (drive flank alone, damper c k1/(k1 +
  // k_c)) and with both flanks loaded.
  for (double torque : {0.1, 10.0}) {
    Harness h(128, torque);
    State6 y = h.equilibrium(0.2);
    double phase = 0.2;
    ASSERT_TRUE(
        h.exact.propagate(y, phase, meshHz(1000), 4e-3, h.drive_force));  // every slice decomposed
    GearRotorParameters changed = params();
    changed.mesh_damping *= 3.0;
    h.exact.setParameters(changed);
    GearRotorModel damper(changed, h.excitation);
    damper.setTorqueInput(torque);
    damper.setMotionInput(MeshMotion{0.0, 0.2, 0.0});
    const State6 y0 = staticEquilibrium(damper, 0.0);
    const std::vector<Piece> pieces(4, Piece{1e-3, meshHz(1500)});
    const State6 got = h.propagated(y0, 0.2, pieces), ref = h.reference(damper, y0, 0.2, pieces);
    EXPECT_LT(relativeError(got, ref), 1e-8) << "torque " << torque;
  }
}

TEST(SlicedModalPropagator, KeptParameterSetsAreTakenBackAsTheyWere) {
  // Parameters A, then B, then A again: A's slices come back with no decomposition, and from the
  // same state they propagate bit for bit as they did before B (they are the same numbers), and
  // within 1e-8 of dopri5 on A's model. A new set takes a never-used one while there is one, then
  // empties the longest unused.
  Harness h(128);
  const GearRotorParameters a = params();
  GearRotorParameters b = a;
  b.bearing_stiffness = {1.3e8, 1.25e8};
  const State6 y0 = h.equilibrium(0.2);
  const std::vector<Piece> pieces(4, Piece{1e-3, meshHz(1500)});  // 4 ms: every slice crossed
  const State6 first = h.propagated(y0, 0.2, pieces);
  const long after_a = h.exact.decompositions();
  EXPECT_EQ(after_a, h.slices->size());
  h.exact.setParameters(b);
  h.propagated(y0, 0.2, pieces);
  EXPECT_EQ(h.exact.decompositions(), 2 * after_a);
  h.exact.setParameters(a);
  EXPECT_EQ(h.exact.keptSetsReused(), 1);
  h.exact.setParameters(a);  // the parameters it has: not a set taken back
  EXPECT_EQ(h.exact.keptSetsReused(), 1);
  const State6 again = h.propagated(y0, 0.2, pieces);
  EXPECT_EQ(h.exact.decompositions(), 2 * after_a) << "A's slices were decomposed again";
  EXPECT_EQ(again, first);
  EXPECT_LT(relativeError(again, h.reference(y0, 0.2, pieces)), 1e-8);
  // Which set makes room: a never-used one while there is one, then the longest unused. Four new
  // sets fill the six (A and B still kept); A used again; a fifth new set must empty B (the
  // longest unused), not A (the first made: what insertion order or a round robin would empty).
  const auto other = [&](int i) {
    GearRotorParameters o = a;
    o.bearing_stiffness = {1.4e8 + 1e6 * i, 1.4e8};
    return o;
  };
  const std::vector<Piece> short_piece{Piece{1e-4, meshHz(1500)}};
  for (int i = 0; i < SlicedModalPropagator::kKeptParameterSets - 2; ++i) {
    h.exact.setParameters(other(i));
    h.propagated(y0, 0.2, short_piece);
  }
  long before = h.exact.decompositions();
  h.exact.setParameters(a);
  h.propagated(y0, 0.2, pieces);
  EXPECT_EQ(h.exact.decompositions(), before)
      << "a new set emptied A while a set had never been used";
  h.exact.setParameters(other(10));  // B, last used before the four, is the longest unused
  h.propagated(y0, 0.2, short_piece);
  h.exact.setParameters(a);
  before = h.exact.decompositions();
  EXPECT_EQ(h.propagated(y0, 0.2, pieces), first);
  EXPECT_EQ(h.exact.decompositions(), before) << "A was emptied, not the longest unused set";
  h.exact.setParameters(b);
  h.propagated(y0, 0.2, pieces);
  EXPECT_EQ(h.exact.decompositions() - before, h.slices->size())
      << "B's set should have been emptied";
  // Taken back as they were only where they are that set's: a set emptied and made again is
  // decomposed afresh (other seeds: the same answer to rounding, not bit for bit).
  h.exact.setParameters(a);
  for (int i = 20; i < 20 + SlicedModalPropagator::kKeptParameterSets; ++i) {
    h.exact.setParameters(other(i));
    h.propagated(y0, 0.2, short_piece);
  }
  h.exact.setParameters(a);
  before = h.exact.decompositions();
  const State6 evicted = h.propagated(y0, 0.2, pieces);
  EXPECT_EQ(h.exact.decompositions() - before, h.slices->size())
      << "A's set should have been emptied";
  EXPECT_LT(relativeError(evicted, first), 1e-12);
}

// Fuzz finding: a reversed motion standing exactly on a period boundary (phase 0, or a phase that
// rounded to 1.0) looked for the slice below in the wrong period, so nextSwitch returned a time in
// the past and dopri5 crawled one ulp per step for ever.
TEST(SlicedExcitation, NextSwitchBackwardsFromAPeriodBoundary) {
  auto slices = std::make_shared<const SlicedMesh>(mesh(), 256);
  for (double phase0 : {0.0, 1.0, 3.0}) {
    const SlicedExcitation e(slices, kTe, 0.0, 1.0, 0.0, MeshMotion{0.184, phase0, -100.0});
    const double top = slices->start(slices->size() - 1);  // the top slice of the period below
    EXPECT_NEAR(e.nextSwitch(0.184), 0.184 + (1.0 - top) / 100.0, 1e-15) << "phase0 = " << phase0;
    // A speed that is all but zero: the switch is far ahead.
    EXPECT_GT(e.nextSwitch(0.184, MeshMotion{0.184, phase0, -5e-101}), 1e90);
  }
}

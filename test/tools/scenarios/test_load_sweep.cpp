// The load_sweep scenario (src/tools/scenarios/load_sweep.hpp) on a perturbed rig whose truth is
// known (test/data/perturbed_servo.yaml: mesh scale 0.8, pinion support 0.7, gear support 1.3,
// T_p 1.2):
//  - the gear encoder carries the static TE of the true rig: per hold, the mean over the hold's
//  last
//    gear turn of x_enc = r_b,p theta_p + r_b,g theta_g (from the quantised readings, mounting
//    errors included) minus the same mean at zero torque equals StaticTeModel::features (the
//    calibration's model at the true parameters) within 1 %, and a closed form built from other
//    parts (the mesh's phase table, BearingSupport solves of the supports) within 2 %;
//  - the staircase (levels, knees, holds), the encoders' mounting errors, the stamp jitter and the
//    torque noise are what the spec says; the same seed gives the same events, bit for bit.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <string>
#include <vector>

#include "drivetrain_stiffness/calibration/static_te_model.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/bearing/bearing_support.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "scenarios/load_sweep.hpp"

using namespace drivetrain_stiffness;

namespace {

const RigConfig& trueRig() {
  static const RigConfig r =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/test/data/perturbed_servo.yaml");
  return r;
}

/// The default scenario (120 rpm, 5 kHz readings, 1 kHz torque, seed 1): 48 s, made once.
const LoadSweep& sweep() {
  static const LoadSweep s = makeLoadSweep(trueRig(), LoadSweepSpec{});
  return s;
}

struct Readings {
  std::vector<double> t, pinion, gear, offset;
};

Readings readingsOf(const LoadSweep& s) {
  Readings r;
  for (const RigEvent& e : s.events) {
    if (!e.motion) continue;
    r.t.push_back(e.t);
    r.pinion.push_back(e.motion->pinion_angle);
    r.gear.push_back(*e.motion->gear_angle);
    r.offset.push_back(e.stamp_offset);
  }
  return r;
}

const Readings& readings() {
  static const Readings r = readingsOf(sweep());
  return r;
}

/// Readings [first, last) of the last gear turn of hold i.
std::pair<long, long> lastTurn(const LoadSweepTruth& truth, std::size_t i, double joint_rate) {
  const LoadSweepLevel& l = truth.levels[i];
  return {std::lround((l.t1 - truth.gear_turn) * joint_rate), std::lround(l.t1 * joint_rate)};
}

/// The encoder TE x = r_b,p theta_p + r_b,g theta_g over the last gear turn of hold i: its mean
/// and its first two mesh harmonics C_k = 2 <x e^{-i 2 pi k phase}> [m], phase = z_p theta_p / 2 pi
/// with the kinematic pinion angle. A gear turn holds 40 mesh periods and both shafts' whole turns,
/// so the mounting errors (shaft orders 1) leave the mean and the mesh harmonics.
struct Window {
  double mean = 0.0;
  std::array<std::complex<double>, 2> harmonic{};
};
Window measured(std::size_t i) {
  const std::array<double, 2> rb = StaticTeModel(trueRig()).baseRadius();
  const auto [a, b] = lastTurn(sweep().truth, i, LoadSweepSpec{}.joint_rate);
  const double omega = LoadSweepSpec{}.speed_rpm * kTwoPi / 60.0, n = static_cast<double>(b - a);
  Window w;
  for (long k = a; k < b; ++k) {
    const double x = rb[0] * readings().pinion[k] + rb[1] * readings().gear[k];
    const double phase = 20.0 * omega * readings().t[k] / kTwoPi;
    w.mean += x / n;
    for (int h = 0; h < 2; ++h)
      w.harmonic[h] += 2.0 * x * std::polar(1.0, -kTwoPi * (h + 1) * phase) / n;
  }
  return w;
}

/// The mean TE at pinion torque T above zero torque, from parts the calibration's model does not
/// use: the mesh's phase table (AntiBacklashMesh::at, the true scale) averaged over 4000 phases
/// with the flank state of each, and each support's exact solution (BearingSupport::solve) at its
/// radial preload and with its share of |F| added, the difference divided by its stiffness_scale.
double closedForm(double torque) {
  const RigConfig& rig = trueRig();
  const AntiBacklashMesh mesh(rig);
  const double force = torque / mesh.geometry().baseRadius(0), fp = mesh.preloadForce();
  const int n = 4000;
  double delta = 0.0;
  for (int i = 0; i < n; ++i) {
    const CompositeMesh c = mesh.at((i + 0.5) / n, force);
    const double k1 = c.k1, kc = c.k_chain;
    if (force * kc > fp * (k1 + kc))
      delta += (force - fp) / k1;  // drive flank only
    else if (force * k1 < -fp * (k1 + kc))
      delta += (force + fp) / kc;  // back flank only
    else
      delta += force / (k1 + kc);  // both
  }
  delta /= n;
  double bearings = 0.0;
  for (const BearingSupportConfig& b : rig.bearings) {
    const BearingSupport support(b.spec, b.arrangement, b.axial_preload, b.interference, b.tilt);
    Vector5d load = Vector5d::Zero();
    load[kUx] = b.radial_preload;
    const BearingSolution free = support.solve(load);
    load[kUx] += b.mesh_load_share * std::abs(force);
    const BearingSolution loaded = support.solve(load);
    bearings +=
        b.mesh_load_share * (loaded.displacement[kUx] - free.displacement[kUx]) / b.stiffness_scale;
  }
  return delta + std::copysign(bearings, force);
}

}  // namespace

TEST(LoadSweep, StaircaseCrossesBothKneesWithHoldsOfWholeGearTurns) {
  const LoadSweepTruth& t = sweep().truth;
  EXPECT_EQ(t.mesh_stiffness_scale, 0.8);
  EXPECT_EQ(t.bearing_scale[0], 0.7);
  EXPECT_EQ(t.bearing_scale[1], 1.3);
  EXPECT_EQ(t.preload_torque, 1.2);
  EXPECT_DOUBLE_EQ(t.gear_turn, 1.0);  // 120 rpm pinion, 20/40 teeth: 60 rpm gear
  // Knees at the true parameters; the reverse one at F = -F_p (1 + k_c/k1).
  StaticTeModel model(trueRig());
  EXPECT_DOUBLE_EQ(t.knee_torque, model.kneeTorque(t.parameters()));
  const double fp = t.preload_torque / model.baseRadius()[1] * model.baseRadius()[0];
  EXPECT_NEAR((t.knee_torque / fp - 1.0) * (-t.reverse_knee_torque / fp - 1.0), 1.0,
              1e-12);               // (k1/kc)(kc/k1)
  ASSERT_EQ(t.levels.size(), 19u);  // 0, 10 up, 0, 6 down, 0
  EXPECT_EQ(t.levels.front().t0, 0.0);
  EXPECT_EQ(t.levels.front().t1, 3.0);  // 3 gear turns unloaded
  EXPECT_EQ(t.duration, 48.0);
  int above = 0, below = 0;
  for (std::size_t i = 1; i < t.levels.size(); ++i) {
    EXPECT_EQ(t.levels[i].t0, t.levels[i - 1].t1);
    EXPECT_NEAR(t.levels[i].t1 - t.levels[i].t0, 2.5, 1e-12);
    // No level within 5 % of a knee.
    EXPECT_GT(std::abs(t.levels[i].torque - t.knee_torque), 0.05 * t.knee_torque) << i;
    EXPECT_GT(std::abs(t.levels[i].torque - t.reverse_knee_torque), -0.05 * t.reverse_knee_torque)
        << i;
    above += t.levels[i].torque > t.knee_torque;
    below += t.levels[i].torque < t.reverse_knee_torque;
  }
  EXPECT_EQ(above, 4);
  EXPECT_EQ(below, 2);
  EXPECT_NEAR(t.levels[10].torque / t.knee_torque, 10.0 / 6.5, 1e-12);
  EXPECT_NEAR(t.levels[17].torque / t.reverse_knee_torque, 6.0 / 4.5, 1e-12);
  EXPECT_EQ(t.levels[11].torque, 0.0);
  EXPECT_EQ(t.levels[18].torque, 0.0);
  // 48 s: 240000 readings at 5 kHz, 48000 torque samples at 1 kHz, one preload.
  EXPECT_EQ(readings().t.size(), 240000u);
  EXPECT_EQ(sweep().te.size(), 240000u);
}

TEST(LoadSweep, GearEncoderCarriesTheTrueStaticTe) {
  const LoadSweepTruth& t = sweep().truth;
  StaticTeModel model(trueRig());
  StiffnessEstimator supports(trueRig());
  const CalibrationVector p = t.parameters();
  const std::array<double, 2> none{{0.0, 0.0}};
  const Window base = measured(0);
  for (std::size_t i = 1; i < t.levels.size(); ++i) {
    const double torque = t.levels[i].torque;
    std::array<double, 2> d{};
    model.shaftDeflection(torque, supports, d);
    const FeatureVector predicted = model.features(p, torque, d, 0.0, none);
    const Window w = measured(i);
    const double mean = w.mean - base.mean, closed = closedForm(torque);
    const double c1 = std::abs(w.harmonic[0] - base.harmonic[0]),
                 c2 = std::abs(w.harmonic[1] - base.harmonic[1]);
    if (torque == 0.0) {
      // Back at zero: the baseline again, to the readings' quantisation (a count is 34 nm at
      // r_b,p).
      std::printf("hold %2zu, T = 0: mean TE %+.1e m above the first zero hold\n", i, mean);
      EXPECT_NEAR(mean, 0.0, 2e-9) << i;
      continue;
    }
    std::printf(
        "hold %2zu, T = %+8.4f N*m: mean TE %+.5e m, model %+.3f %%, closed form %+.3f %%; |C1| "
        "%.4e m, model "
        "%+.2f %%; |C2| %.4e m, model %+.2f %%\n",
        i, torque, mean, 100.0 * (mean / predicted[0] - 1.0), 100.0 * (mean / closed - 1.0), c1,
        100.0 * (c1 / predicted[1] - 1.0), c2, 100.0 * (c2 / predicted[2] - 1.0));
    // Measured: within 0.11 % of both at every hold (the sampled mesh steps and the 256-slice mesh
    // of the truth dynamics).
    EXPECT_NEAR(mean, predicted[0], 0.01 * std::abs(predicted[0]))
        << "hold " << i << " at " << torque << " N*m";
    EXPECT_NEAR(mean, closed, 0.02 * std::abs(closed))
        << "hold " << i << " at " << torque << " N*m";
    // The mesh harmonics too, within the error of sampling a TE with steps (the tooth-pair
    // switches) at 125 fixed phases per mesh period (5000 Hz / 40 Hz): measured within 0.6 % (C1)
    // and 4.6 % (C2); the exact waveform sampled so gives +-3 % on |C2| depending on where the
    // samples fall against the switches, its period integral the model's.
    EXPECT_NEAR(c1, predicted[1], 0.01 * predicted[1] + 1e-9) << "hold " << i;
    EXPECT_NEAR(c2, predicted[2], 0.06 * predicted[2] + 1e-9) << "hold " << i;
  }
}

TEST(LoadSweep, EncoderMountingErrorsAreInRangeAndInTheReadings) {
  const LoadSweepTruth& t = sweep().truth;
  const Readings& r = readings();
  const double omega = 120.0 * kTwoPi / 60.0, ratio = 0.5;
  // Over the unloaded hold (3 gear turns, 6 pinion turns, 15000 readings): the reading minus the
  // kinematic angle, fitted with sin and cos of the angle, gives eps and psi (the gear's TE at zero
  // torque has only mesh orders there, orthogonal over whole turns).
  const long n = std::lround(3.0 * 5000.0);
  for (int shaft = 0; shaft < 2; ++shaft) {
    EXPECT_GE(t.eccentricity[shaft], 10.0 * kArcsecond);
    EXPECT_LE(t.eccentricity[shaft], 20.0 * kArcsecond);
    EXPECT_GE(t.eccentricity_phase[shaft], 0.0);
    EXPECT_LT(t.eccentricity_phase[shaft], kTwoPi);
    double a = 0.0, b = 0.0;
    for (long k = 0; k < n; ++k) {
      const double theta = (shaft == 0 ? 1.0 : -ratio) * omega * r.t[k];
      const double residual = (shaft == 0 ? r.pinion[k] : r.gear[k]) - theta;
      a += 2.0 * residual * std::sin(theta) / n;
      b += 2.0 * residual * std::cos(theta) / n;
    }
    EXPECT_NEAR(std::hypot(a, b), t.eccentricity[shaft], 0.01 * t.eccentricity[shaft]) << shaft;
    EXPECT_NEAR(std::remainder(std::atan2(b, a) - t.eccentricity_phase[shaft], kTwoPi), 0.0, 0.02)
        << shaft;
  }
}

TEST(LoadSweep, StampJitterAndTorqueNoiseAsSpecified) {
  const LoadSweepTruth& t = sweep().truth;
  double max_jitter = 0.0;
  for (double o : readings().offset) {
    ASSERT_LE(std::abs(o), 20e-6);
    max_jitter = std::max(max_jitter, std::abs(o));
  }
  EXPECT_GT(max_jitter, 19.9e-6);
  // The published torque minus the true one, in units of its sigma = 0.005 |T| + 1e-3 N*m.
  double sum = 0.0, sum2 = 0.0;
  long n = 0;
  std::size_t level = 0;
  for (const RigEvent& e : sweep().events) {
    if (!e.torque) continue;
    while (level + 1 < t.levels.size() && e.t >= t.levels[level + 1].t0) ++level;
    const double truth = t.levels[level].torque;
    const double z = (*e.torque - truth) / (0.005 * std::abs(truth) + 1e-3);
    sum += z;
    sum2 += z * z;
    ++n;
  }
  ASSERT_EQ(n, 48000);
  EXPECT_NEAR(sum / n, 0.0, 0.03);              // 5 sigma of the mean of 48000
  EXPECT_NEAR(std::sqrt(sum2 / n), 1.0, 0.02);  // about 6 sigma of the RMS
}

TEST(LoadSweep, SameSeedSameEventsOtherSeedOnlyOtherNoise) {
  // A short one: every hold scaled to 2 s in all (the truth does not depend on the seed).
  LoadSweepSpec spec;
  spec.duration = 2.0;
  const LoadSweep a = makeLoadSweep(trueRig(), spec), b = makeLoadSweep(trueRig(), spec);
  spec.seed = 2;
  const LoadSweep c = makeLoadSweep(trueRig(), spec);
  ASSERT_EQ(a.events.size(), b.events.size());
  ASSERT_EQ(a.events.size(), c.events.size());
  EXPECT_EQ(a.truth.duration, 2.0);
  EXPECT_EQ(a.te, c.te);  // bit for bit
  long differ = 0;
  for (std::size_t i = 0; i < a.events.size(); ++i) {
    const RigEvent &x = a.events[i], &y = b.events[i], &z = c.events[i];
    ASSERT_EQ(x.t, y.t);
    ASSERT_EQ(x.torque, y.torque);
    ASSERT_EQ(x.stamp_offset, y.stamp_offset);
    ASSERT_EQ(x.preload.size(), y.preload.size());
    ASSERT_EQ(x.motion.has_value(), y.motion.has_value());
    if (x.motion) {
      ASSERT_EQ(x.motion->pinion_angle, y.motion->pinion_angle);
      ASSERT_EQ(x.motion->gear_angle, y.motion->gear_angle);
      ASSERT_EQ(x.motion->pinion_velocity, y.motion->pinion_velocity);
      ASSERT_EQ(x.gear_velocity, y.gear_velocity);
      differ += x.motion->gear_angle != z.motion->gear_angle || x.stamp_offset != z.stamp_offset;
    } else {
      ASSERT_EQ(x.t, z.t);
      differ += x.torque != z.torque;
    }
  }
  EXPECT_GT(differ, static_cast<long>(a.events.size() * 9 / 10));
}

TEST(LoadSweep, RefusesBadSpecsAndRigsNamingThem) {
  auto refuses = [](const RigConfig& rig, const LoadSweepSpec& spec, const std::string& field) {
    try {
      makeLoadSweep(rig, spec);
      ADD_FAILURE() << "accepted; expected a refusal naming " << field;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  LoadSweepSpec spec;
  spec.speed_rpm = -1.0;
  refuses(trueRig(), spec, "speed_rpm");
  spec = LoadSweepSpec{};
  spec.stamp_jitter = 1e-3;
  refuses(trueRig(), spec, "stamp_jitter");
  spec = LoadSweepSpec{};
  spec.overdrive = 1.0;
  refuses(trueRig(), spec, "overdrive");
  RigConfig rig = trueRig();
  rig.dynamics.present = false;
  refuses(rig, LoadSweepSpec{}, "dynamics");
  rig = trueRig();
  rig.anti_backlash.spring_stiffness = 0.0;
  refuses(rig, LoadSweepSpec{}, "anti_backlash");
}

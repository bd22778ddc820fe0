#include "drivetrain_stiffness/core/scenes/scenes.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/rig_excitation.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

// Kahraman & Singh style excitation (gear.md section 3, the Fraunhofer-SCAI regression case):
// k(tau) = k0 [1 - a1 cos(W tau) - a2 cos(2 W tau) - a3 cos(3 W tau)], dead zone of half-gap 1,
// force F_m + F_te W^2 cos(W tau), unit equivalent mass.
class OscillatorExcitation : public GearExcitation {
 public:
  OscillatorExcitation(double w, double f_m, double f_te, std::array<double, 3> ripple)
      : w_(w), f_m_(f_m), f_te_(f_te), ripple_(ripple) {}
  void at(double t, MeshInstant& out) const override {
    out.k_drive = 1.0 - ripple_[0] * std::cos(w_ * t) - ripple_[1] * std::cos(2 * w_ * t) -
                  ripple_[2] * std::cos(3 * w_ * t);
    out.k_back = 0.0;
    out.preload_force = 0.0;
    out.backlash = 1.0;
    out.te = out.te_rate = 0.0;
    out.drive_force = f_m_ + f_te_ * w_ * w_ * std::cos(w_ * t);
    out.phase = std::fmod(w_ * t / kTwoPi, 1.0);
  }
  double nextSwitch(double) const override { return INFINITY; }

 private:
  double w_, f_m_, f_te_;
  std::array<double, 3> ripple_;
};

Scene oscillatorScene(const std::string& name, double w, double zeta, double f_m, double f_te,
                      std::array<double, 3> ripple, int periods, const std::string& description) {
  // Unit equivalent mass (r_p = r_g = 1, I_p = I_g = 2 gives m_s = 1); the shafts are made
  // immovable (huge masses, no bearing stiffness) so the model reduces to the single DOF x.
  GearRotorParameters p;
  p.pinion_mass = p.gear_mass = 1e12;
  p.pinion_inertia = p.gear_inertia = 2.0;
  p.pinion_base_radius = p.gear_base_radius = 1.0;
  p.mesh_damping = 2.0 * zeta;
  Scene s;
  s.name = name;
  s.description = description;
  s.model = std::make_shared<GearRotorModel>(
      p, std::make_shared<OscillatorExcitation>(w, f_m, f_te, ripple));
  s.initial = State6::Zero();
  s.initial[2] = 1.0 + f_m;  // start just in contact
  s.duration = periods * kTwoPi / w;
  s.output_interval = 0.015;  // gear.md: the regression case samples at d tau = 0.015
  s.duration = std::round(s.duration / s.output_interval) * s.output_interval;
  s.transient = 0.5 * s.duration;
  s.suggested_step = 0.015 / 5;
  s.units = "dimensionless";
  return s;
}

// Radial stiffness of the supports on each shaft at the mean torque, from the bearing model.
std::array<double, 2> bearingStiffness(const RigConfig& rig, double torque) {
  StiffnessEstimator estimator(rig);
  const StiffnessEstimate& e = estimator.setTorque(torque);
  std::array<double, 2> k{{0.0, 0.0}};
  for (std::size_t i = 0; i < e.supports.size(); ++i)
    k[rig.bearings[i].shaft] += e.supports[i].solution.radialStiffness();
  return k;
}

struct RigSceneSetup {
  RigConfig rig;
  RigExcitationSpec excitation;
  double duration = 0.03;
  double bearing_scale = 1.0;  ///< multiply the bearing-model stiffness
  bool parametric = false;     ///< choose the speed for mesh frequency = 2 f_1
};

/// The rotor of a rig scene: the mesh table, its mean stiffness and the model's parameters.
struct RigRotor {
  std::shared_ptr<AntiBacklashMesh> mesh;
  double k_mean = 0.0;
  GearRotorParameters p;
};

RigRotor rigRotor(const RigSceneSetup& setup) {
  const RigConfig& rig = setup.rig;
  RigRotor r;
  r.mesh = std::make_shared<AntiBacklashMesh>(rig);
  r.k_mean = meanMeshStiffness(*r.mesh);
  std::array<double, 2> kb = bearingStiffness(rig, setup.excitation.torque.mean);
  for (double& k : kb) {
    // near-rigid scenes give the bearing stiffness as a ratio to the mesh
    k = setup.bearing_scale > 1e3 ? setup.bearing_scale * r.k_mean : k * setup.bearing_scale;
  }
  r.p = rigRotorParameters(rig, *r.mesh, kb);
  return r;
}

/// Explicit methods: 20 steps per period of the stiffest mode, rounded to divide the output
/// interval.
double suggestedStep(const RigRotor& r, double output_interval) {
  const GearRotorParameters& p = r.p;
  const double w_max = std::sqrt(std::max({(r.k_mean + p.bearing_stiffness[0]) / p.pinion_mass,
                                           (r.k_mean + p.bearing_stiffness[1]) / p.gear_mass,
                                           2.0 * r.k_mean / p.equivalentMass()}));
  const double h = kTwoPi / w_max / 20.0;
  return output_interval / std::ceil(output_interval / h);
}

Scene rigScene(const std::string& name, const std::string& description, RigSceneSetup setup) {
  const RigConfig& rig = setup.rig;
  const RigRotor rotor = rigRotor(setup);
  const std::shared_ptr<AntiBacklashMesh>& mesh = rotor.mesh;
  const double k_mean = rotor.k_mean;
  const GearRotorParameters& p = rotor.p;
  if (setup.parametric) {
    // Lowest natural frequency of the linearised system (docs/model.md), mesh frequency = 2 f_1.
    Eigen::Matrix3d mm =
        Eigen::Vector3d(p.pinion_mass, p.gear_mass, p.equivalentMass()).asDiagonal();
    const Eigen::Matrix3d kk = meshBearingMatrix(k_mean, p.bearing_stiffness);
    const double f1 =
        std::sqrt(
            Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d>(kk, mm).eigenvalues()[0]) /
        kTwoPi;
    setup.excitation.speed = 2.0 * f1 * kTwoPi / rig.gears.teeth[0];
  }
  Scene s;
  s.name = name;
  s.description = description;
  // Start half a sample into the mesh period: the output grid (32 per period) then never lands on
  // the drive-flank switch at phase 0, where a sample would be ambiguous (delta is continuous in
  // the full model but the quasi-static deflection jumps there).
  setup.excitation.initial_phase = 0.5 / 32.0;
  auto excitation = std::make_shared<RigExcitation>(mesh, p, setup.excitation);
  s.model = std::make_shared<GearRotorModel>(p, excitation);
  s.initial = staticEquilibrium(*s.model, 0.0);
  // 32 samples per mesh period (an exact divisor, so the exponential method can run on the same
  // grid): 10.7 kHz for the nominal 333 Hz mesh, well above the mesh harmonics that matter.
  const double period = 1.0 / excitation->meshFrequency();
  s.output_interval = period / 32.0;
  s.duration = std::round(setup.duration / period) * period;
  s.transient = 0.3 * s.duration;
  s.suggested_step = suggestedStep(rotor, s.output_interval);
  return s;
}

// The sliced model along a scene's measured motion: reading interval k is SlicedExcitation k, its
// motion anchored at reading k, so the slice lookup, TE and drive force are SlicedExcitation's own.
// The right-hand side jumps at the slice boundaries and at the readings (the speed, hence de/dt,
// changes there): both are time events.
class MotionExcitation : public GearExcitation {
 public:
  MotionExcitation(const SceneMotion& m, double torque_gain, double torque)
      : interval_(m.reading_interval) {
    for (std::size_t k = 0; k + 1 < m.readings(); ++k) {
      pieces_.emplace_back(
          m.slices, m.te_amplitude, m.backlash, torque_gain, 0.0,
          MeshMotion{static_cast<double>(k) * interval_, m.phase[k], m.meshFrequency(k)}, torque);
    }
    if (pieces_.empty()) throw InvalidInput("scene motion: needs at least two readings");
  }
  void at(double t, MeshInstant& out) const override { pieces_[piece(t)].at(t, out); }
  double nextSwitch(double t) const override {
    const std::size_t k = piece(t);
    const double next = pieces_[k].nextSwitch(t);
    return k + 1 < pieces_.size() ? std::min(next, readingTime(k + 1)) : next;
  }

 private:
  double readingTime(std::size_t k) const { return static_cast<double>(k) * interval_; }
  /// k with readingTime(k) <= t < readingTime(k + 1); the first before 0, the last after the end.
  std::size_t piece(double t) const {
    if (!(t > 0.0)) return 0;
    std::size_t k = static_cast<std::size_t>(
        std::min(std::floor(t / interval_), static_cast<double>(pieces_.size() - 1)));
    while (k + 1 < pieces_.size() && readingTime(k + 1) <= t) ++k;
    while (k > 0 && readingTime(k) > t) --k;
    return k;
  }
  double interval_;
  std::vector<SlicedExcitation> pieces_;
};

/// [rad/s] from [rpm].
double radPerSecond(double rpm) { return rpm * kTwoPi / 60.0; }

/// The scenes whose speed changes: the pinion speed profile over [0, T] by name (the profiles of
/// drivetrain_rig_sim's speed scenarios, src/tools/scenarios/rig_scenarios.cpp; speed_steps' ramps
/// are T/20, 50 ms at the 1 s default, as the scenario's).
SpeedProfile motionProfile(const std::string& name, double T) {
  if (name == "run_up") return SpeedProfile(SpeedRamp{0.0, radPerSecond(6000.0), 0.0, T});
  if (name == "speed_steps") {
    return SpeedProfile(SpeedSteps{radPerSecond(500.0),
                                   {{T / 4.0, radPerSecond(1000.0)},
                                    {T / 2.0, radPerSecond(2000.0)},
                                    {3.0 * T / 4.0, radPerSecond(4000.0)}},
                                   T / 20.0});
  }
  return SpeedProfile(SpeedReversal{radPerSecond(1000.0), 0.0, T});  // reverse
}

Scene motionScene(const std::string& name, const std::string& description, RigSceneSetup setup,
                  double duration) {
  constexpr double kReading =
      1e-3;  // encoder readings at 1 kHz, as drivetrain_rig_sim's joint_rate
  if (!(duration >= 0.02 && duration <= 100.0)) {
    throwInvalid("duration", duration, "a motion scene needs 0.02 s (20 readings) to 100 s");
  }
  const long readings = std::lround(duration / kReading);
  const double T = static_cast<double>(readings) * kReading;
  const RigRotor rotor = rigRotor(setup);
  auto motion = std::make_shared<SceneMotion>();
  motion->pinion_speed = motionProfile(name, T);
  motion->pinion_teeth = setup.rig.gears.teeth[0];
  motion->initial_phase = 0.5 / 32.0;  // off the drive-flank switch at phase 0, as rigScene
  motion->reading_interval = kReading;
  double fastest = 0.0;  // [rad/s]
  for (long k = 0; k <= readings; ++k) {
    motion->phase.push_back(motion->closedFormPhase(static_cast<double>(k) * kReading));
    fastest =
        std::max(fastest, std::abs(motion->pinion_speed.speed(static_cast<double>(k) * kReading)));
  }
  // The node's default ~motion_slices.
  motion->slices = std::make_shared<const SlicedMesh>(rotor.mesh, 256);
  motion->te_amplitude = setup.excitation.te_amplitude;
  motion->backlash = setup.excitation.backlash;
  // The live node's load follows the input (RigExcitationSpec::balanced_load): F_d = T / r_p.
  const double torque_gain = 1.0 / rotor.p.pinion_base_radius;
  motion->drive_force = torque_gain * setup.excitation.torque.mean;
  Scene s;
  s.name = name;
  s.description = description;
  s.model = std::make_shared<GearRotorModel>(
      rotor.p,
      std::make_shared<MotionExcitation>(*motion, torque_gain, setup.excitation.torque.mean));
  s.initial = staticEquilibrium(*s.model, 0.0);
  // At least 32 samples per mesh period at the fastest speed, a whole number per reading.
  const double fastest_mesh_hz = fastest * motion->pinion_teeth / kTwoPi;
  s.output_interval = kReading / std::max(1.0, std::ceil(32.0 * fastest_mesh_hz * kReading));
  s.duration = T;
  // The first tenth discarded (the start from static equilibrium rings for a few ms), cut half a
  // sample off the grid so that fixed-step samples, whose times are sums of steps, fall on the same
  // side.
  s.transient = (std::round(0.1 * T / s.output_interval) + 0.5) * s.output_interval;
  s.suggested_step = suggestedStep(rotor, s.output_interval);
  s.motion = std::move(motion);
  return s;
}

/// The dimensionless oscillator scenes (kahraman_singh, chaotic); nullopt for any other name.
std::optional<Scene> oscillatorSceneNamed(const std::string& name) {
  if (name == "kahraman_singh") {
    return oscillatorScene(
        name, 0.5, 0.05, 0.1, 0.01, {0.2, 0.1, 0.05}, 200,
        "dimensionless backlash oscillator, k = 1 - 0.2 cos W t - 0.1 cos 2W t - 0.05 cos 3W t, "
        "zeta 0.05, F_m 0.1, F_te 0.01, W = 0.5 (gear.md section 3)");
  }
  if (name == "chaotic") {
    return oscillatorScene(name, 1.4, 0.02, 0.02, 0.02, {0.3, 0.0, 0.0}, 300,
                           "backlash oscillator at low load and damping with 30 % stiffness "
                           "ripple: impacts, sensitive "
                           "dependence on the initial state (a 1e-9 perturbation grows to O(1): "
                           "positive Lyapunov exponent)");
  }
  return std::nullopt;
}

/// The rig's scene setup from its dynamics block.
RigSceneSetup sceneSetup(const RigConfig& rig_in) {
  RigSceneSetup setup;
  setup.rig = rig_in;
  const DynamicsConfig& d = rig_in.dynamics;
  setup.excitation.speed = d.speed_rpm * kTwoPi / 60.0;
  setup.excitation.te_amplitude = d.transmission_error_amplitude;
  setup.excitation.backlash = d.backlash;
  setup.excitation.torque.mean = d.torque;
  return setup;
}

/// The rig's scenes at a constant speed; nullopt for any other name.
std::optional<Scene> constantSpeedScene(const std::string& name, RigSceneSetup setup,
                                        const DynamicsConfig& d) {
  if (name == "nominal") {
    return rigScene(name, "seed 000 Table 1: 1000 rpm, 0.1 N m, TE at mesh frequency", setup);
  }
  if (name == "torque_steps") {
    setup.excitation.torque.kind = TorqueProfile::Kind::kSteps;
    setup.excitation.torque.steps = {{5e-3, 0.5}, {10e-3, -0.3}, {15e-3, d.torque}};
    setup.duration = 0.02;
    return rigScene(name, "torque steps 0.1 -> 0.5 -> -0.3 -> 0.1 N m at 5, 10, 15 ms", setup);
  }
  if (name == "low_preload") {
    setup.rig.anti_backlash.preload_torque = 0.01;
    setup.excitation.torque.kind = TorqueProfile::Kind::kSine;
    setup.excitation.torque.amplitude = 0.8 * d.torque;
    setup.excitation.torque.frequency = 500.0;
    setup.duration = 0.02;
    return rigScene(name,
                    "spring preload 0.01 N m (F_p 0.89 N) under 0.1 +- 0.08 N m at 500 Hz: the g2 "
                    "flank separates and re-impacts",
                    setup);
  }
  if (name == "bearing_rattle") {
    // Zero mean load: only a torque fluctuation pushes the shafts (a TE alone is absorbed by the
    // torsional coordinate, whose mode is far above the mesh frequency). +-0.05 N m at 500 Hz moves
    // a free shaft about F/(m w^2) = 26 um, more than its 10 um clearance: it rattles.
    setup.rig.dynamics.bearing_clearance = {10e-6, 10e-6};
    setup.excitation.torque.mean = 0.0;
    setup.excitation.torque.kind = TorqueProfile::Kind::kSine;
    setup.excitation.torque.amplitude = 0.05;
    setup.excitation.torque.frequency = 500.0;
    setup.duration = 0.02;
    return rigScene(name,
                    "zero mean torque, +-0.05 N m at 500 Hz, 10 um radial bearing clearance: the "
                    "shafts rattle in the clearance",
                    setup);
  }
  if (name == "near_rigid_bearings") {
    setup.bearing_scale = 1e4;
    setup.duration = 0.003;
    return rigScene(name, "bearing stiffness 1e4 x the mean mesh stiffness", setup);
  }
  if (name == "parametric_resonance") {
    setup.parametric = true;
    setup.duration = 0.01;
    return rigScene(name, "mesh frequency at twice the lowest natural frequency", setup);
  }
  return std::nullopt;
}

/// The motion scenes (run_up, speed_steps, reverse) over T [s].
Scene namedMotionScene(const std::string& name, const RigSceneSetup& setup, const DynamicsConfig& d,
                       double T) {
  const std::string held = ", torque " + formatValue(d.torque) +
                           " N m held, sliced mesh (256 slices), encoder readings at 1 kHz";
  if (name == "run_up")
    return motionScene(name, "pinion 0 -> 6000 rpm linearly over the scene" + held, setup, T);
  if (name == "speed_steps") {
    return motionScene(
        name,
        "pinion 500, 1000, 2000, 4000 rpm, a quarter of the scene each, each step a ramp of "
        "1/20 of the scene" +
            held,
        setup, T);
  }
  return motionScene(
      name,
      "pinion 1000 rpm cos(2 pi t / T): through zero at T/4 to -1000 rpm at T/2, zero again "
      "at 3T/4, back to +1000 rpm" +
          held,
      setup, T);
}

}  // namespace

std::vector<std::string> sceneNames() {
  return {"nominal",
          "torque_steps",
          "low_preload",
          "bearing_rattle",
          "near_rigid_bearings",
          "parametric_resonance",
          "kahraman_singh",
          "chaotic",
          "run_up",
          "speed_steps",
          "reverse"};
}

std::vector<std::string> motionSceneNames() { return {"run_up", "speed_steps", "reverse"}; }

double SceneMotion::closedFormPhase(double t) const {
  return initial_phase + pinion_teeth * pinion_speed.angle(t) / kTwoPi;
}

Scene makeScene(const std::string& name, const RigConfig& rig_in, double duration) {
  const std::vector<std::string> moving = motionSceneNames();
  const bool motion = std::find(moving.begin(), moving.end(), name) != moving.end();
  if (duration != 0.0 && !motion) {
    throwInvalid("duration", duration,
                 "only the motion scenes (run_up, speed_steps, reverse) take a duration");
  }
  if (std::optional<Scene> s = oscillatorSceneNamed(name)) return std::move(*s);
  if (!rig_in.dynamics.present)
    throw InvalidInput("scene '" + name + "': the gearbox file has no 'dynamics:' block");
  const RigSceneSetup setup = sceneSetup(rig_in);
  if (std::optional<Scene> s = constantSpeedScene(name, setup, rig_in.dynamics))
    return std::move(*s);
  if (motion)
    return namedMotionScene(name, setup, rig_in.dynamics, duration > 0.0 ? duration : 1.0);
  throw InvalidInput("scene = '" + name +
                     "': unknown (nominal, torque_steps, low_preload, bearing_rattle, "
                     "near_rigid_bearings, parametric_resonance, kahraman_singh, chaotic, run_up, "
                     "speed_steps, reverse)");
}

State6 propagateMotionScene(const Scene& scene, const SlicedModalPropagator& exact,
                            const IntegratorOptions& fallback, const Observer& observe,
                            IntegrationStats* stats) {
  if (!scene.motion)
    throw InvalidInput("scene '" + scene.name +
                       "': at a constant speed, no measured motion to follow");
  const SceneMotion& m = *scene.motion;
  const double h = scene.output_interval;
  const long per_reading = std::lround(m.reading_interval / h);
  const long n = std::lround(scene.duration / h);
  if (per_reading < 1 || n > per_reading * static_cast<long>(m.readings() - 1)) {
    throw InvalidInput("scene '" + scene.name + "': the output grid does not fit the readings");
  }
  IntegrationStats st;
  const long crossed = exact.slicesCrossed();
  State6 y = scene.initial;
  if (observe) observe(0.0, y);
  double phase = m.phase[0];
  for (long i = 0; i < n; ++i) {
    const std::size_t k = static_cast<std::size_t>(i / per_reading);
    const long into = i % per_reading;  // samples since reading k
    if (into == 0) phase = m.phase[k];  // re-anchored at every reading, as the node does
    const double f = m.meshFrequency(k);
    const double t = static_cast<double>(i) * h;
    // As the node propagates: exact through the changes of the contacts, dopri5 on the same sliced
    // model and motion through each moment in no linear regime (fallbacks: the sample intervals
    // that needed it).
    const long stretches =
        propagateMeasured(exact, y, phase, f, t, static_cast<double>(i + 1) * h, m.drive_force,
                          [&](double t0, double t1, State6& z, double& p) {
                            z = integrate(*scene.model, IntegratorMethod::kDopri5, fallback, t0, z,
                                          t1, t1 - t0, nullptr);
                            p += f * (t1 - t0);
                          });
    if (stretches > 0 && st.fallbacks++ == 0) st.fallback_from = t;
    if (observe) observe(static_cast<double>(i + 1) * h, y);
  }
  st.steps = exact.slicesCrossed() - crossed;
  if (stats) *stats = st;
  return y;
}

std::vector<SweepPoint> sweepOscillator(const OscillatorSweepSpec& spec,
                                        const std::vector<double>& frequencies) {
  requireInHalfOpenRange("sweep.zeta", spec.zeta, 0.0, 1.0);
  requireFinite("sweep.mean_force", spec.mean_force);
  requireFinite("sweep.te_force", spec.te_force);
  if (spec.settle < 1 || spec.measure < 1)
    throw InvalidInput("sweep: settle and measure must be >= 1 period");
  GearRotorParameters p;
  p.pinion_mass = p.gear_mass = 1e12;
  p.pinion_inertia = p.gear_inertia = 2.0;
  p.pinion_base_radius = p.gear_base_radius = 1.0;
  p.mesh_damping = 2.0 * spec.zeta;
  IntegratorOptions o;
  o.relative_tolerance = 1e-9;
  o.absolute_tolerance = 1e-11;
  o.max_step = 0.1;
  o.divergence_limit = 1e3;
  State6 y = State6::Zero();
  y[2] = 1.0 + spec.mean_force;
  std::vector<SweepPoint> out;
  for (double w : frequencies) {
    requirePositive("sweep.frequency", w);
    const GearRotorModel model(
        p, std::make_shared<OscillatorExcitation>(w, spec.mean_force, spec.te_force, spec.ripple));
    const double period = kTwoPi / w;
    SweepPoint pt;
    pt.frequency = w;
    pt.min_x = INFINITY;
    pt.max_x = -INFINITY;
    y = integrate(model, IntegratorMethod::kDopri5, o, 0.0, y,
                  (spec.settle + spec.measure) * period, period / 50,
                  [&](double t, const State6& s) {
                    if (t >= spec.settle * period) {
                      pt.min_x = std::min(pt.min_x, s[2]);
                      pt.max_x = std::max(pt.max_x, s[2]);
                    }
                  });
    pt.peak_to_peak = pt.max_x - pt.min_x;
    pt.regime = pt.min_x < -1.0  ? "double_sided_impact"
                : pt.min_x < 1.0 ? "single_sided_impact"
                                 : "no_impact";
    out.push_back(pt);
  }
  return out;
}

}  // namespace drivetrain_stiffness

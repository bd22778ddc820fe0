#include "rig_scenarios.hpp"

#include <algorithm>  // NOLINT(build/include_subdir)

#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/speed_profile.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "rig_encoder.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

std::vector<PreloadSetting> preloadOfAll(const RigConfig& rig, double axial) {
  std::vector<PreloadSetting> out;
  for (const BearingSupportConfig& b : rig.bearings) {
    out.push_back({b.name, axial, b.radial_preload, b.interference.inner, b.interference.outer});
  }
  return out;
}

double configuredAxial(const RigConfig& rig) {
  return rig.bearings.empty() ? 0.0 : rig.bearings.front().axial_preload;
}

/// [rad/s] from [rpm]: one revolution (2 pi rad) per minute (60 s).
double radPerSecond(double rpm) { return rpm * kTwoPi / 60.0; }

bool isSpeedScenario(const std::string& s) {
  return s == "run_up" || s == "coast_down" || s == "speed_steps" || s == "reverse";
}

/// The pinion's speed: the speed scenarios' own profiles; the others run at the gearbox's nominal
/// speed (dynamics.speed_rpm, 1000 rpm without a dynamics block), as their torque assumes.
SpeedProfile scenarioSpeed(const RigConfig& rig, const ScenarioSpec& spec) {
  const std::string& s = spec.name;
  const double T = spec.duration;
  if (s == "run_up") return SpeedProfile(SpeedRamp{0.0, radPerSecond(6000.0), 0.0, T});
  if (s == "coast_down") return SpeedProfile(SpeedRamp{radPerSecond(6000.0), 0.0, 0.0, T});
  if (s == "speed_steps") {
    // 500, 1000, 2000, 4000 rpm, a quarter of the duration each, every step a 50 ms linear ramp.
    const double ramp = 0.05;
    if (!(T / 4.0 >= ramp))
      throwInvalid("duration", T,
                   "speed_steps needs >= 0.2 s (four dwells, each at least its 0.05 s ramp)");
    return SpeedProfile(SpeedSteps{radPerSecond(500.0),
                                   {{T / 4.0, radPerSecond(1000.0)},
                                    {T / 2.0, radPerSecond(2000.0)},
                                    {3.0 * T / 4.0, radPerSecond(4000.0)}},
                                   ramp});
  }
  // +1000 rpm, zero at T/4, -1000 rpm at T/2, zero at 3T/4, +1000 rpm at T: 1000 rpm cos(2 pi t /
  // T).
  if (s == "reverse") return SpeedProfile(SpeedReversal{radPerSecond(1000.0), 0.0, T});
  return SpeedProfile(radPerSecond(rig.dynamics.present ? rig.dynamics.speed_rpm : 1000.0));
}

/// Encoder readings of both shafts at spec.joint_rate from t = 0, as events of their own.
void addEncoderEvents(const RigConfig& rig, const ScenarioSpec& spec, const SpeedProfile& speed,
                      std::vector<RigEvent>& events) {
  requireNonNegative("joint_rate", spec.joint_rate);
  if (spec.joint_rate == 0.0) return;
  const long n = std::lround(spec.duration * spec.joint_rate);
  if (n < 2 || n > 100000000) {
    throw InvalidInput("duration * joint_rate = " + std::to_string(n) +
                       ": must be in [2, 1e8] samples (joint_rate 0: none)");
  }
  requirePositive("gears.teeth[0]", rig.gears.teeth[0]);
  requirePositive("gears.teeth[1]", rig.gears.teeth[1]);
  const double ratio = static_cast<double>(rig.gears.teeth[0]) / rig.gears.teeth[1];  // z_p / z_g
  const double dt = 1.0 / spec.joint_rate;
  for (long k = 0; k < n; ++k) {
    RigEvent e;
    e.t = k * dt;
    const EncoderSample reading = readEncoders(speed, e.t, ratio, spec.joint_velocity);
    e.motion = reading.motion;
    e.gear_velocity = reading.gear_velocity;
    events.push_back(std::move(e));
  }
}

/// The faults scenario's injected inputs, each at its own time after 1/4 of the duration, so every
/// rule is visible in the counters; from 3/4 on the stamps run 0.6 duration behind.
void injectFaults(const RigConfig& rig, const ScenarioSpec& spec, double dt, double mean,
                  std::vector<RigEvent>& events) {
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  const double t1 = 0.25 * spec.duration;
  events.push_back({t1 + 0.1 * dt, nan, {}});
  events.push_back({t1 + 0.2 * dt, inf, {}});
  events.push_back({t1 + 0.3 * dt, 1e6, {}});                // absurd (over max_abs_torque)
  events.push_back({t1 + 0.4 * dt, mean, {}, true});         // zero stamp
  events.push_back({t1 + 0.5 * dt, mean, {}, false, -0.5});  // 0.5 s late: out of order
  for (int i = 0; i < 5; ++i)
    events.push_back({t1 + 0.6 * dt, mean, {}, false, 0.0});    // burst, equal stamps
  std::vector<PreloadSetting> bad = preloadOfAll(rig, -100.0);  // negative preload
  events.push_back({t1 + 0.7 * dt, std::nullopt, bad});
  RigEvent after_loss{t1 + 0.8 * dt, mean, {}};  // 3 torque messages lost on the way
  after_loss.lost_before = 3;
  events.push_back(after_loss);
  RigEvent wrong_frame{t1 + 0.9 * dt, mean, {}};  // torque about the gear's axis
  wrong_frame.frame_id = "gear";
  events.push_back(wrong_frame);
  // From 3/4 on, the stamps run 0.6 duration behind (a recording that looped; more than the
  // default ~stamp_jump_back of 1 s for durations over 1.7 s): one reset, then accepted.
  for (RigEvent& e : events) {
    if (e.t >= 0.75 * spec.duration && !e.zero_stamp) e.stamp_offset -= 0.6 * spec.duration;
  }
}

}  // namespace

std::string scenarioHelp() {
  return "torque_ripple: mean torque (gearbox dynamics.torque) with 6th and 12th shaft-order "
         "ripple (5 % and 2 %) at "
         "the nominal speed, preload re-sent at 1 Hz\n"
         "torque_steps: 0.05, 0.1, 0.2, -0.1 (reversal onto the anti-backlash flank) and 0.1 N*m, "
         "equal dwell\n"
         "preload_ramp: axial preload of every support ramped 200 -> 2000 N at 10 Hz, constant "
         "torque\n"
         "speed_sweep: mesh-order torque ripple (5 %) whose frequency sweeps 5 -> 11 kHz, through "
         "the transverse "
         "modes (use --rate >= 25000)\n"
         "faults: torque_ripple with a NaN, an Inf, an absurd torque, a zero stamp, an "
         "out-of-order stamp, a burst of "
         "equal stamps and a jump back of the stamps by 0.6 duration (a looped recording) "
         "injected\n"
         "(the five above at the gearbox's constant dynamics.speed_rpm; the four below at constant "
         "torque "
         "dynamics.torque, preload sent once)\n"
         "run_up: pinion speed 0 -> 6000 rpm linearly over the duration\n"
         "coast_down: pinion speed 6000 -> 0 rpm linearly over the duration\n"
         "speed_steps: 500, 1000, 2000, 4000 rpm, a quarter of the duration each, each step a 50 "
         "ms linear ramp\n"
         "reverse: +1000 rpm through zero (at 1/4) to -1000 rpm (at 1/2) and back (zero at 3/4, "
         "+1000 rpm at the "
         "end): 1000 rpm cos(2 pi t / duration); the torque keeps its sign\n"
         "load_sweep: a calibration recording whose true rig is the --config one (load_sweep.hpp): "
         "120 rpm "
         "(--speed-rpm), a torque staircase across the anti-backlash knee both ways, the gear "
         "encoder carrying the "
         "true rig's TE, encoder mounting errors, stamp jitter and torque noise from --seed; joint "
         "rate 5000 Hz by "
         "default; its natural length unless --duration is given (which scales every hold)\n";
}

SpeedProfile scenarioSpeedProfile(const RigConfig& rig, const ScenarioSpec& spec) {
  return scenarioSpeed(rig, spec);
}

std::vector<RigEvent> makeScenario(const RigConfig& rig, const ScenarioSpec& spec) {
  requirePositive("duration", spec.duration);
  requirePositive("rate", spec.torque_rate);
  const long n = std::lround(spec.duration * spec.torque_rate);
  if (n < 2 || n > 100000000)
    throw InvalidInput("duration * rate = " + std::to_string(n) + ": must be in [2, 1e8] samples");
  const double dt = 1.0 / spec.torque_rate;
  const double mean =
      rig.dynamics.present ? rig.dynamics.torque : 0.1;  // seed 000 Table 1: 0.1 N*m
  const double shaft_hz = (rig.dynamics.present ? rig.dynamics.speed_rpm : 1000.0) / 60.0;
  std::vector<RigEvent> events;
  const std::string& s = spec.name;
  // The encoders first: at equal times a reading precedes the torque (the stable sort below keeps
  // that order), and the faults' jump back of the stamps moves the readings with the rest.
  addEncoderEvents(rig, spec, scenarioSpeed(rig, spec), events);
  auto ripple = [&](double t) {
    // Servo motors ripple at multiples of six per electrical revolution; with one pole pair
    // that is the 6th and 12th shaft order.
    return mean * (1.0 + 0.05 * std::sin(kTwoPi * 6.0 * shaft_hz * t) +
                   0.02 * std::sin(kTwoPi * 12.0 * shaft_hz * t));
  };
  if (s == "torque_ripple" || s == "faults") {
    for (long k = 0; k < n; ++k) {
      const double t = k * dt;
      if (k % std::max(1L, std::lround(spec.torque_rate)) == 0)
        events.push_back({t, std::nullopt, preloadOfAll(rig, configuredAxial(rig))});
      events.push_back({t, ripple(t), {}});
    }
    if (s == "faults") injectFaults(rig, spec, dt, mean, events);
  } else if (s == "torque_steps") {
    const double levels[] = {0.5, 1.0, 2.0, -1.0, 1.0};
    events.push_back({0.0, std::nullopt, preloadOfAll(rig, configuredAxial(rig))});
    for (long k = 0; k < n; ++k) {
      const int step = std::min<int>(4, static_cast<int>(5 * k / n));
      events.push_back({k * dt, mean * levels[step], {}});
    }
  } else if (s == "preload_ramp") {
    const long every = std::max(1L, std::lround(spec.torque_rate / 10.0));
    for (long k = 0; k < n; ++k) {
      const double t = k * dt;
      if (k % every == 0)
        events.push_back({t, std::nullopt, preloadOfAll(rig, 200.0 + 1800.0 * t / spec.duration)});
      events.push_back({t, mean, {}});
    }
  } else if (s == "speed_sweep") {
    // Linear chirp 5 -> 11 kHz: phase = 2 pi (f0 t + (f1 - f0) t^2 / (2 T)).
    const double f0 = 5000.0, f1 = 11000.0;
    events.push_back({0.0, std::nullopt, preloadOfAll(rig, configuredAxial(rig))});
    for (long k = 0; k < n; ++k) {
      const double t = k * dt;
      const double phase = kTwoPi * (f0 * t + 0.5 * (f1 - f0) * t * t / spec.duration);
      events.push_back({t, mean * (1.0 + 0.05 * std::sin(phase)), {}});
    }
  } else if (isSpeedScenario(s)) {
    // The speed follows the scenario's profile (the encoder events above); the torque is constant.
    events.push_back({0.0, std::nullopt, preloadOfAll(rig, configuredAxial(rig))});
    for (long k = 0; k < n; ++k) events.push_back({k * dt, mean, {}});
  } else if (s == "load_sweep") {
    throw InvalidInput(
        "scenario = 'load_sweep': made by makeLoadSweep (load_sweep.hpp), which takes a seed and a "
        "speed");
  } else {
    throw InvalidInput("scenario = '" + s + "': unknown; one of:\n" + scenarioHelp());
  }
  // In send order, as a rig numbers its messages (header.seq) and rosbag::View plays them.
  std::stable_sort(events.begin(), events.end(),
                   [](const RigEvent& a, const RigEvent& b) { return a.t < b.t; });
  return events;
}

}  // namespace drivetrain_stiffness

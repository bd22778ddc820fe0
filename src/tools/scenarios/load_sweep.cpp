#include "load_sweep.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>

#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "rig_encoder.hpp"    // NOLINT(build/include_subdir)
#include "seeded_stream.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

enum StreamId : std::uint32_t { kEncoderStream = 1, kJitterStream = 2, kTorqueStream = 3 };

double gearTurn(const RigConfig& rig, double speed_rpm) {
  // The gear turns z_p / z_g as fast as the pinion.
  return 60.0 / speed_rpm * static_cast<double>(rig.gears.teeth[1]) / rig.gears.teeth[0];
}

void validate(const RigConfig& rig, const LoadSweepSpec& s) {
  requirePositive("speed_rpm", s.speed_rpm);
  if (s.speed_rpm > 1e4) throwInvalid("speed_rpm", s.speed_rpm, "must be <= 10000 rpm");
  requirePositive("rate", s.torque_rate);
  requirePositive("joint_rate", s.joint_rate);
  requireNonNegative("duration", s.duration);
  requirePositive("baseline_turns", s.baseline_turns);
  requirePositive("step_turns", s.step_turns);
  if (s.positive_levels < 1) throwInvalid("positive_levels", s.positive_levels, "must be >= 1");
  if (s.negative_levels < 1) throwInvalid("negative_levels", s.negative_levels, "must be >= 1");
  if (!(s.overdrive > 1.0 && s.overdrive <= 10.0))
    throwInvalid("overdrive", s.overdrive, "must be in (1, 10]");
  requireNonNegative("eccentricity_min", s.eccentricity_min);
  if (!(s.eccentricity_max >= s.eccentricity_min && s.eccentricity_max < 1e-2)) {
    throwInvalid("eccentricity_max", s.eccentricity_max, "must be in [eccentricity_min, 1e-2) rad");
  }
  requireNonNegative("stamp_jitter", s.stamp_jitter);
  if (!(s.stamp_jitter < 0.5 / s.joint_rate))
    throwInvalid("stamp_jitter", s.stamp_jitter, "must be below half a reading interval");
  requireNonNegative("torque_noise", s.torque_noise);
  requireNonNegative("torque_noise_floor", s.torque_noise_floor);
  requirePositive("lead_in", s.lead_in);
  requireNonNegative("dwell", s.dwell);
  if (s.dwell > 1e5) throwInvalid("dwell", s.dwell, "must be <= 1e5 s");
  requireFinite("dwell_torque", s.dwell_torque);
  requirePositive("gears.teeth[0]", rig.gears.teeth[0]);
  requirePositive("gears.teeth[1]", rig.gears.teeth[1]);
  if (!rig.dynamics.present)
    throw InvalidInput(
        "dynamics: load_sweep needs the gearbox's 'dynamics:' block (the true rig's TE)");
  if (!(rig.anti_backlash.spring_stiffness > 0.0)) {
    throw InvalidInput(
        "anti_backlash.spring_stiffness = 0: load_sweep crosses the anti-backlash knee; an "
        "ordinary gear has none");
  }
}

/// The stiffness_scale of each shaft's supports: the calibration has one scale per shaft, so the
/// supports of a shaft must share it.
std::array<double, 2> shaftScales(const RigConfig& rig) {
  std::array<double, 2> scale{{0.0, 0.0}};
  for (const BearingSupportConfig& b : rig.bearings) {
    double& s = scale.at(static_cast<std::size_t>(b.shaft));
    if (s == 0.0) s = b.stiffness_scale;
    if (b.stiffness_scale != s) {
      throwInvalid("bearings[" + b.name + "].stiffness_scale", b.stiffness_scale,
                   "differs from another support of the same shaft (" + formatValue(s) +
                       "): load_sweep's truth has one scale per shaft");
    }
  }
  for (int i = 0; i < 2; ++i) {
    if (scale[i] == 0.0)
      throw InvalidInput(std::string("bearings: no support on the ") +
                         (i == 0 ? "pinion" : "gear") + " shaft");
  }
  return scale;
}

/// The torque staircase: [0] the baseline, then the positive levels, a zero, the negative levels
/// and a final zero. The levels of each direction are evenly spaced, h apart, with the knee halfway
/// between two of them (no level sits on the knee, where the features' slope changes): the knee is
/// at (m + 1/2) h, m + 1/2 the half-integer nearest to levels / overdrive, so the top level is
/// about overdrive x the knee (10 levels at 1.5: h = knee / 6.5, top 1.54 knee; 6 levels: h = knee
/// / 4.5, top 1.33 knee). Levels beyond `limit` [N*m] in magnitude (what the rig's bearings carry)
/// are left out.
std::vector<double> torqueLevels(const LoadSweepSpec& s, double knee, double reverse_knee,
                                 double limit) {
  auto ladder = [&](int n, double k) {
    const long m = std::max(0L, std::min<long>(n - 1, std::lround(n / s.overdrive - 0.5)));
    const double h = k / (static_cast<double>(m) + 0.5);
    std::vector<double> out;
    for (int i = 1; i <= n; ++i) {
      if (std::abs(i * h) <= limit) out.push_back(i * h);
    }
    return out;
  };
  std::vector<double> levels{0.0};
  for (double t : ladder(s.positive_levels, knee)) levels.push_back(t);
  levels.push_back(0.0);
  for (double t : ladder(s.negative_levels, reverse_knee)) levels.push_back(t);
  levels.push_back(0.0);
  return levels;
}

std::int64_t nanoseconds(double t) { return std::llround(t * 1e9); }

/// Collects the truth dynamics' torsional coordinate on the readings' grid.
class TruthSink : public PipelineSink {
 public:
  TruthSink(std::int64_t epoch_ns, double joint_rate, long lead, std::vector<double>& te,
            std::vector<char>& filled)
      : epoch_ns_(epoch_ns), joint_rate_(joint_rate), lead_(lead), te_(te), filled_(filled) {}
  double correction = 0.0;  ///< [m] c(T) of the torque the dynamics hold (encoderOffset)

  void transmissionError(Stamp stamp, const DynamicsSample& sample, const SampleContext&) override {
    // The output grid is the readings' grid (output_rate = joint_rate, the mesh period a whole
    // number of readings, the dynamics started on a reading): sample j at j / joint_rate after the
    // start, to the nanosecond rounding of the stamps.
    const std::int64_t rel = stamp.ns - epoch_ns_;
    const long j = std::lround(static_cast<double>(rel) * 1e-9 * joint_rate_);
    if (std::llabs(rel - nanoseconds(j / joint_rate_)) > 1) {
      throw InvalidInput("load_sweep: a truth sample at " + std::to_string(rel) +
                         " ns after the start is off the readings' grid");
    }
    const long k = j - lead_;
    if (k < 0 || k >= static_cast<long>(te_.size())) return;
    te_[static_cast<std::size_t>(k)] = sample.state[2] + correction;
    ++filled_[static_cast<std::size_t>(k)];
  }

 private:
  std::int64_t epoch_ns_;
  double joint_rate_;
  long lead_;
  std::vector<double>& te_;
  std::vector<char>& filled_;
};

void require(InputOutcome outcome, const RigPipeline& pipeline, const char* what, double t) {
  if (outcome != InputOutcome::kAccepted) {
    throw InvalidInput(std::string("load_sweep: the truth dynamics refused the ") + what +
                       " at t = " + formatValue(t) + " s (" + toString(outcome) +
                       "): " + pipeline.counters().last_event);
  }
}

}  // namespace

CalibrationVector LoadSweepTruth::parameters() const {
  CalibrationVector p;
  p << mesh_stiffness_scale, bearing_scale[0], bearing_scale[1], preload_torque, 0.0;
  return p;
}

double loadSweepNaturalDuration(const RigConfig& rig, const LoadSweepSpec& s) {
  validate(rig, s);
  const int holds =
      s.positive_levels + s.negative_levels + 2;  // after the baseline: levels and two zeros
  return (s.baseline_turns + holds * s.step_turns) * gearTurn(rig, s.speed_rpm);
}

namespace {

/// The largest torque [N*m] the rig's supports carry (ISO 76 contact pressure; the seed's reach it
/// near 11.2 N*m), by 40 bisections of [0, 100] N*m.
double carriedTorque(const RigConfig& rig) {
  double carried = 0.0, refused = 100.0;
  StiffnessEstimator probe(rig);
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (carried + refused);
    try {
      probe.setTorque(mid);
      carried = mid;
    } catch (const UnreachableLoad&) {
      refused = mid;
    } catch (const InvalidInput&) {
      refused = mid;
    }
  }
  return carried;
}

/// Sets the knees of the TRUE rig (static_te_model.hpp): the back half lifts at F = F_p (1 +
/// k1/k_c), the drive half at F = -F_p (1 + k_c/k1), F = T / r_b,pinion, F_p = T_p / r_b,gear,
/// period means. Throws InvalidInput naming anti_backlash.preload_torque if there is no knee.
void setKnees(const StaticTeModel& model, LoadSweepTruth& truth) {
  const std::array<double, 2> rb = model.baseRadius();
  const CalibrationVector p = truth.parameters();
  truth.knee_torque = model.kneeTorque(p);
  const double fp_torque = truth.preload_torque / rb[1] * rb[0];  // F_p r_b,p [N*m]
  if (!(truth.knee_torque > fp_torque && fp_torque > 0.0)) {
    throwInvalid("anti_backlash.preload_torque", truth.preload_torque,
                 "gives no knee to sweep across");
  }
  const double k1_over_kc = truth.knee_torque / fp_torque - 1.0;
  truth.reverse_knee_torque = -fp_torque * (1.0 + 1.0 / k1_over_kc);
}

/// Fills truth.levels and truth.duration: the holds, their boundaries on the torque samples' grid
/// (the true torque steps there), stretched by `stretch`. Levels beyond 0.96 x `carried` (4 % left
/// for the published torque's noise, 6 sigma at 0.5 %) are left out; the knee must stay below the
/// limit with at least one level above. Returns the number of torque samples. Throws InvalidInput
/// naming the field.
long placeHolds(const LoadSweepSpec& s, double stretch, double carried, LoadSweepTruth& truth) {
  const double limit = 0.96 * carried;
  const std::vector<double> levels =
      torqueLevels(s, truth.knee_torque, truth.reverse_knee_torque, limit);
  const long above =
      std::count_if(levels.begin(), levels.end(), [&](double t) { return t > truth.knee_torque; });
  if (above < 1) {
    throwInvalid("anti_backlash.preload_torque", truth.preload_torque,
                 "puts the knee (" + formatValue(truth.knee_torque) +
                     " N*m) beyond 0.96 x the torque the bearings carry (" + formatValue(carried) +
                     " N*m): no level above the knee");
  }
  double end = 0.0;
  long sample = 0;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    end += stretch * (i == 0 ? s.baseline_turns : s.step_turns) * truth.gear_turn;
    const long next = std::lround(end * s.torque_rate);
    if (next <= sample)
      throwInvalid("duration", s.duration, "leaves a hold without a torque sample");
    truth.levels.push_back({sample / s.torque_rate, next / s.torque_rate, levels[i]});
    sample = next;
  }
  if (s.dwell > 0.0) {  // the constant-load dwell after the sweep
    if (std::abs(s.dwell_torque) > limit) {
      throwInvalid(
          "dwell_torque", s.dwell_torque,
          "beyond 0.96 x the torque the bearings carry (" + formatValue(carried) + " N*m)");
    }
    end += s.dwell;
    const long next = std::lround(end * s.torque_rate);
    if (next <= sample) throwInvalid("dwell", s.dwell, "shorter than a torque sample");
    truth.levels.push_back({sample / s.torque_rate, next / s.torque_rate, s.dwell_torque});
    sample = next;
  }
  truth.duration = truth.levels.back().t1;
  return sample;
}

/// The rig's configured preloads, as the recording sends them.
std::vector<PreloadSetting> configuredPreloads(const RigConfig& rig) {
  std::vector<PreloadSetting> preload;
  for (const BearingSupportConfig& b : rig.bearings) {
    preload.push_back(
        {b.name, b.axial_preload, b.radial_preload, b.interference.inner, b.interference.outer});
  }
  return preload;
}

/// The truth's pipeline options: the output grid is the readings' grid (output_rate = joint_rate)
/// and the bearings' stiffness is exact at every torque.
PipelineOptions truthOptions(const LoadSweepSpec& s) {
  PipelineOptions options;
  options.output_rate = s.joint_rate;
  options.limits.load_tolerance = 0.0;  // exact bearing stiffness at every torque
  options.pinion_speed_rpm = s.speed_rpm;
  return options;
}

/// The true rig with its nominal speed rounded so that one mesh period is a whole number of
/// reading intervals (the dynamics round their grid to divide the mesh period); the speed only
/// sets the grid, the measured motion drives the mesh phase.
RigConfig truthRig(const RigConfig& rig, const LoadSweepSpec& s) {
  RigConfig true_rig = rig;
  const double per_period =
      std::max(1.0, std::round(s.joint_rate * 60.0 / (s.speed_rpm * rig.gears.teeth[0])));
  true_rig.dynamics.speed_rpm = 60.0 * s.joint_rate / (per_period * rig.gears.teeth[0]);
  return true_rig;
}

/// The encoder TE offset c(T) [m] the truth adds to the dynamics' torsional coordinate at the
/// torque [N*m].
///
/// The encoder TE is x_enc = x + c(T). The dynamics' torsional coordinate x = delta - x_p + x_g + e
/// (gear_rotor_model.hpp) carries the shafts' static deflection with the TANGENT bearing stiffness
/// k_shaft(T) that they linearise about: F / k_shaft per shaft. That is right for the small
/// perturbations about the operating point (the mesh-frequency motion), but a static offset from
/// zero load needs the SECANT: the exact solution's deflection u(F_0 + |F|) - u(F_0), which a
/// Hertzian bearing (stiffening with load) makes smaller than F / k_tangent. So
///   c(T) = sum_shaft [ d_shaft(T) / scale_shaft - F / k_shaft(T) ],   F = T / r_b,p (signed),
/// with d = StaticTeModel::shaftDeflection (scale-1 secant deflections {-x_p, x_g}, signed with the
/// torque) divided by the true rig's scale of that shaft, and k_shaft the stiffness the dynamics
/// run with (DynamicsEstimator::bearingStiffness(): it takes up a change only beyond 1 %, as its 1
/// % grid value, so it can differ from the estimator's shaftRadialStiffness() by that much; the
/// estimator's would leave up to 1 % of the bearing deflection in x_enc). c is constant per hold;
/// across a step it jumps with the torque while x settles over the dynamics' transient
/// (milliseconds).
double encoderOffset(StaticTeModel& model, const RigPipeline& pipeline,
                     const std::array<double, 2>& scale, double torque) {
  std::array<double, 2> shafts{};
  model.shaftDeflection(torque, pipeline.estimator(), shafts);
  const std::array<double, 2>& k = pipeline.dynamics()->bearingStiffness();
  const double force = model.meshForce(torque);
  double c = 0.0;
  for (int i = 0; i < 2; ++i) c += shafts[i] / scale[i] - force / k[i];
  return c;
}

/// Throws InvalidInput if the truth dynamics were interrupted or a reading did not get exactly one
/// truth sample.
void checkTruth(const RigPipeline& pipeline, const std::vector<char>& filled) {
  const PipelineCounters& counters = pipeline.counters();
  if (counters.dynamics_errors != 0 || counters.gap_restarts != 0 ||
      counters.motion_timeouts != 0) {
    throw InvalidInput("load_sweep: the truth dynamics were interrupted (" + counters.last_event +
                       ")");
  }
  for (std::size_t k = 0; k < filled.size(); ++k) {
    if (filled[k] != 1) {
      throw InvalidInput("load_sweep: reading " + std::to_string(k) + " got " +
                         std::to_string(filled[k]) +
                         " truth samples (the output grid missed the readings)");
    }
  }
}

/// Fills out.te [m]: the true rig's 3-DOF dynamics under the true torque and the exact motion,
/// plus the encoder offset c(T), at each of the n_joint readings. The truth runs from -lead_in (a
/// whole number of readings) on its own clock from 10 s, the dynamics starting at static
/// equilibrium at the first torque input, on a reading.
void runTruth(const RigConfig& rig, const LoadSweepSpec& s, StaticTeModel& model,
              const std::array<double, 2>& scale, const std::vector<PreloadSetting>& preload,
              long n_joint, LoadSweep& out) {
  const LoadSweepTruth& truth = out.truth;
  const double omega = s.speed_rpm * kTwoPi / 60.0;
  RigPipeline pipeline(truthRig(rig, s), truthOptions(s));

  out.te.assign(static_cast<std::size_t>(n_joint), 0.0);
  std::vector<char> filled(static_cast<std::size_t>(n_joint), 0);
  const long lead = std::max(1L, std::lround(s.lead_in * s.joint_rate));
  const std::int64_t epoch_ns = 10000000000LL;
  auto stampOf = [&](long j) {
    return Stamp{epoch_ns + nanoseconds(j / s.joint_rate)};
  };  // j: readings since -lead
  TruthSink sink(epoch_ns, s.joint_rate, lead, out.te, filled);
  auto reading = [&](long j) {
    MotionInput m;
    m.pinion_angle = omega * ((j - lead) / s.joint_rate);
    m.pinion_velocity = omega;
    return m;
  };
  // -lead_in: the first reading, the configured preloads, the true torque (0).
  require(pipeline.motion(stampOf(0), reading(0), sink), pipeline, "reading", -lead / s.joint_rate);
  require(pipeline.preload(stampOf(0), preload, sink), pipeline, "preload", -lead / s.joint_rate);
  require(pipeline.torque(stampOf(0), truth.levels.front().torque, sink), pipeline, "torque",
          -lead / s.joint_rate);
  if (!pipeline.dynamics() || !pipeline.dynamics()->started())
    throw InvalidInput("load_sweep: the truth dynamics did not start");
  sink.correction = encoderOffset(model, pipeline, scale, truth.levels.front().torque);
  std::size_t level = 1;  // the next step
  const long j_end = lead + n_joint;
  for (long j = 1; j < j_end; ++j) {
    const Stamp at = stampOf(j);
    // Steps before this reading, then the reading (its sample is emitted with the torque held
    // before it), then a step at the same instant: the rig's send order.
    auto stepsUpTo = [&](bool inclusive) {
      while (level < truth.levels.size()) {
        const std::int64_t step_ns =
            epoch_ns + nanoseconds(truth.levels[level].t0 + lead / s.joint_rate);
        if (step_ns > at.ns || (!inclusive && step_ns == at.ns)) break;
        const double torque = truth.levels[level].torque;
        require(pipeline.torque(Stamp{step_ns}, torque, sink), pipeline, "torque",
                truth.levels[level].t0);
        sink.correction = encoderOffset(model, pipeline, scale, torque);
        ++level;
      }
    };
    stepsUpTo(false);
    require(pipeline.motion(at, reading(j), sink), pipeline, "reading", (j - lead) / s.joint_rate);
    stepsUpTo(true);
  }
  checkTruth(pipeline, filled);
}

/// Appends the n_joint encoder readings to out.events and draws truth.eccentricity{,_phase}:
/// theta_p kinematic (exact), theta_g from the true TE (x_enc = r_b,p theta_p + r_b,g theta_g, the
/// gear's angle falling when the pinion's rises), each with its mounting error eps sin(theta +
/// psi), then the 2^20-count grid. Stamps: the true time plus a uniform jitter.
void recordReadings(const RigConfig& rig, const LoadSweepSpec& s, const std::array<double, 2>& rb,
                    long n_joint, LoadSweep& out) {
  LoadSweepTruth& truth = out.truth;
  const double omega = s.speed_rpm * kTwoPi / 60.0;
  SeededStream encoders(s.seed, kEncoderStream), jitter(s.seed, kJitterStream);
  for (int i = 0; i < 2; ++i) {
    truth.eccentricity[i] = encoders.uniform(s.eccentricity_min, s.eccentricity_max);
    truth.eccentricity_phase[i] = encoders.uniform(0.0, kTwoPi);
  }
  const double ratio = static_cast<double>(rig.gears.teeth[0]) / rig.gears.teeth[1];
  for (long k = 0; k < n_joint; ++k) {
    RigEvent e;
    e.t = k / s.joint_rate;
    const double theta_p = omega * e.t;
    const double theta_g = (out.te[static_cast<std::size_t>(k)] - rb[0] * theta_p) / rb[1];
    MotionInput m;
    m.pinion_angle = quantiseEncoderAngle(
        theta_p + truth.eccentricity[0] * std::sin(theta_p + truth.eccentricity_phase[0]));
    m.gear_angle = quantiseEncoderAngle(
        theta_g + truth.eccentricity[1] * std::sin(theta_g + truth.eccentricity_phase[1]));
    if (s.joint_velocity) {
      m.pinion_velocity = omega;
      e.gear_velocity = -ratio * omega;
    }
    e.motion = m;
    e.stamp_offset = jitter.uniform(-s.stamp_jitter, s.stamp_jitter);
    out.events.push_back(std::move(e));
  }
}

/// Appends the n_torque torque samples: the true staircase sampled at torque_rate, plus Gaussian
/// noise of sigma = torque_noise |T| + torque_noise_floor.
void recordTorque(const LoadSweepSpec& s, const LoadSweepTruth& truth, long n_torque,
                  std::vector<RigEvent>& events) {
  SeededStream noise(s.seed, kTorqueStream);
  std::size_t level = 0;
  for (long k = 0; k < n_torque; ++k) {
    const double t = k / s.torque_rate;
    while (level + 1 < truth.levels.size() &&
           std::lround(truth.levels[level + 1].t0 * s.torque_rate) <= k)
      ++level;
    const double torque = truth.levels[level].torque;
    const double sigma = s.torque_noise * std::abs(torque) + s.torque_noise_floor;
    events.push_back({t, torque + sigma * noise.normal(), {}});
  }
}

}  // namespace

LoadSweep makeLoadSweep(const RigConfig& rig, const LoadSweepSpec& s) {
  const double natural = loadSweepNaturalDuration(rig, s);  // validates
  const std::array<double, 2> scale = shaftScales(rig);
  LoadSweep out;
  LoadSweepTruth& truth = out.truth;
  truth.mesh_stiffness_scale = rig.mesh_stiffness_scale;
  truth.bearing_scale = scale;
  truth.preload_torque = rig.anti_backlash.preload_torque;
  truth.gear_turn = gearTurn(rig, s.speed_rpm);
  StaticTeModel model(rig);
  setKnees(model, truth);

  const double stretch = s.duration > 0.0 ? s.duration / natural : 1.0;
  const long n_torque = placeHolds(s, stretch, carriedTorque(rig), truth);
  const long n_joint = std::lround(truth.duration * s.joint_rate);
  if (n_torque > 100000000 || n_joint > 100000000) {
    throw InvalidInput("load_sweep: " + std::to_string(n_torque) + " torque samples and " +
                       std::to_string(n_joint) + " readings: at most 1e8 each");
  }
  const std::vector<PreloadSetting> preload = configuredPreloads(rig);
  runTruth(rig, s, model, scale, preload, n_joint, out);

  out.events.reserve(static_cast<std::size_t>(n_joint + n_torque + 1));
  recordReadings(rig, s, model.baseRadius(), n_joint, out);
  out.events.push_back({0.0, std::nullopt, preload});
  recordTorque(s, truth, n_torque, out.events);
  // In send order; at equal times a reading first, then the preload, then the torque.
  std::stable_sort(out.events.begin(), out.events.end(),
                   [](const RigEvent& a, const RigEvent& b) { return a.t < b.t; });
  return out;
}

}  // namespace drivetrain_stiffness

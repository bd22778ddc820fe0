// drivetrain_calibration_mc: the calibration's Monte Carlo over rigs whose truth is known
// (docs/calibration.md section 6). Each run draws a true rig from the nominal gearbox (mesh scale
// 0.8-1.2, each shaft's bearing scale 0.7-1.3, T_p +-20 %), records a load_sweep on it (the truth
// from the 3-DOF dynamics, 2^20-count encoders with 10-20 arcsec mounting errors, stamp jitter,
// 0.5 % torque noise: load_sweep.hpp), and runs the nominal gearbox's pipeline with its calibration
// over the recording, in process (what drivetrain_replay would do with the bag). It prints one JSON
// line per run and a summary: the errors against the truth and how often the 95 % bounds cover it.
// ROS-free and deterministic for a seed.
//
//   drivetrain_calibration_mc --config config/gearboxes/seed_servo.yaml --runs 50 --seed 1
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "load_sweep.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

constexpr double k95 = 1.959963984540054;

/// The rig with its calibration block (the defaults when the file has none).
RigConfig withCalibration(RigConfig rig) {
  if (!rig.calibration.present) {
    CalibrationConfig c;
    c.present = true;
    c.preload_torque = {rig.anti_backlash.preload_torque, 0.2 * rig.anti_backlash.preload_torque};
    rig.calibration = c;
  }
  return rig;
}

/// Feeds the recording to `pipeline` as drivetrain_replay would (stamps from the event times and
/// their jitter, in send order).
/// With `mark` >= 0, `at_mark` gets the calibration's estimate as it stands when the recording
/// reaches t = mark (the dwell's start).
void replay(const LoadSweep& sweep, RigPipeline& pipeline, PipelineSink& sink, double mark = -1.0,
            CalibrationEstimate* at_mark = nullptr) {
  constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;
  bool marked = !(mark >= 0.0 && at_mark);
  for (const RigEvent& e : sweep.events) {
    if (!marked && e.t >= mark) {
      *at_mark = pipeline.calibrator()->estimate();
      marked = true;
    }
    const Stamp stamp{kEpoch + std::llround((e.t + e.stamp_offset) * 1e9)};
    pipeline.observeClock(stamp, sink);
    if (e.motion) pipeline.motion(stamp, *e.motion, sink);
    if (!e.preload.empty()) pipeline.preload(stamp, e.preload, sink);
    if (e.torque) pipeline.torque(stamp, *e.torque, sink, {"rig", 0, e.frame_id});
  }
}

/// With --windows: one line per closed window (outcome, torque, NIS, the estimate).
struct WindowLog : PipelineSink {
  bool enabled = false;
  void calibration(Stamp, const CalibrationEstimate& e) override {
    if (!enabled) return;
    std::cout << nlohmann::json{{"window", e.windows},
                                {"outcome", toString(e.outcome)},
                                {"torque", e.window_torque},
                                {"nis", e.nis},
                                {"mesh_stiffness_scale", e.value[kMeshScale]},
                                {"preload_torque", e.value[kPreloadTorque]},
                                {"preload_torque_std", e.std[kPreloadTorque]},
                                {"measured", {e.measured[0], e.measured[1], e.measured[2]}},
                                {"predicted", {e.predicted[0], e.predicted[1], e.predicted[2]}}}
                     .dump()
              << "\n";
  }
};

/// The median of the values (the mean of the two middle ones for an even count; 0 for none).
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid)));
}

/// The command line.
struct MonteCarloArgs {
  std::string config = "config/gearboxes/seed_servo.yaml";
  int runs = 50;
  std::uint64_t seed = 1;
  double speed = 120.0;
  bool windows = false;
  double dwell = 0.0, dwell_torque = 3.0;
};

/// A true rig drawn about the nominal one: mesh scale 0.8-1.2, each shaft's bearing scale
/// 0.7-1.3, T_p +-20 %.
RigConfig drawTruth(const RigConfig& nominal, std::mt19937_64& draw,
                    std::uniform_real_distribution<double>& uni) {
  RigConfig truth = nominal;
  truth.mesh_stiffness_scale = 0.8 + 0.4 * uni(draw);
  const double pinion_scale = 0.7 + 0.6 * uni(draw), gear_scale = 0.7 + 0.6 * uni(draw);
  for (BearingSupportConfig& b : truth.bearings)
    b.stiffness_scale = b.shaft == 0 ? pinion_scale : gear_scale;
  truth.anti_backlash.preload_torque =
      nominal.anti_backlash.preload_torque * (0.8 + 0.4 * uni(draw));
  return truth;
}

/// The truth's series compliance [m/N] at the reference torque tr [N*m], from the same static
/// model as the calibration. shaftDeflection solves the true rig's supports at scale 1; the scales
/// are in p.
double trueCompliance(const RigConfig& truth, const CalibrationVector& p, double tr) {
  StaticTeModel model(truth);
  StiffnessEstimator supports(truth);
  std::array<double, 2> d{};
  model.shaftDeflection(tr, supports, d);
  return model.features(p, tr, d, 0.0, {0.0, 0.0})[0] / model.meshForce(tr);
}

/// The drift over the dwell: each estimate's move from `before` to `e` in units of its std at the
/// dwell's start and end. Sets run_worst to the largest move [sigmas at the start].
nlohmann::json dwellDrift(const CalibrationEstimate& e, const CalibrationEstimate& before,
                          double& run_worst) {
  nlohmann::json drift;
  run_worst = 0.0;
  for (int i : {kMeshScale, kPreloadTorque, kTeOffset}) {
    const double move = std::abs(e.value[i] - before.value[i]);
    const double sigmas = move / std::max(before.std[i], 1e-300);
    drift[calibrationName(i)] = {{"move", move},
                                 {"sigmas_start", sigmas},
                                 {"sigmas_end", move / std::max(e.std[i], 1e-300)}};
    run_worst = std::max(run_worst, sigmas);
  }
  const double cmove = std::abs(e.series_compliance - before.series_compliance);
  drift["series_compliance"] = {
      {"move", cmove}, {"sigmas_start", cmove / std::max(before.series_compliance_std, 1e-300)}};
  run_worst = std::max(run_worst, cmove / std::max(before.series_compliance_std, 1e-300));
  drift["windows"] = e.windows - before.windows;
  drift["updates"] = e.updates - before.updates;
  return drift;
}

/// One run's errors against the truth and whether the 95 % bounds cover it.
struct RunErrors {
  double mesh = 0.0, tp = 0.0, compliance = 0.0;  ///< relative errors
  bool covered_mesh = false, covered_tp = false, covered_compliance = false;
  bool flags_right = false;  ///< mesh and T_p identified, the bearing scales not
};

RunErrors runErrors(const CalibrationEstimate& e, const CalibrationVector& p, double compliance) {
  RunErrors r;
  r.mesh = e.value[kMeshScale] / p[kMeshScale] - 1.0;
  r.tp = e.value[kPreloadTorque] / p[kPreloadTorque] - 1.0;
  r.compliance = e.series_compliance / compliance - 1.0;
  r.covered_mesh = std::abs(e.value[kMeshScale] - p[kMeshScale]) <= k95 * e.std[kMeshScale];
  r.covered_tp =
      std::abs(e.value[kPreloadTorque] - p[kPreloadTorque]) <= k95 * e.std[kPreloadTorque];
  r.covered_compliance =
      std::abs(e.series_compliance - compliance) <= k95 * e.series_compliance_std;
  r.flags_right = e.identified[kMeshScale] && e.identified[kPreloadTorque] &&
                  !e.identified[kPinionBearingScale] && !e.identified[kGearBearingScale];
  return r;
}

/// One run's JSON line, without its dwell and window counts.
nlohmann::json runLine(int run, const CalibrationVector& p, const CalibrationEstimate& e,
                       double compliance, const RunErrors& r) {
  nlohmann::json line;
  line["run"] = run;
  for (int i = 0; i < kCalibrationSize; ++i) {
    line["truth"][calibrationName(i)] = p[i];
    line["estimate"][calibrationName(i)] = e.value[i];
    line["std"][calibrationName(i)] = e.std[i];
    line["identified"][calibrationName(i)] = e.identified[i];
  }
  line["series_compliance"] = {
      {"truth", compliance}, {"estimate", e.series_compliance}, {"std", e.series_compliance_std}};
  line["error"] = {{"mesh_stiffness_scale", r.mesh},
                   {"preload_torque", r.tp},
                   {"series_compliance", r.compliance}};
  line["covered"] = {{"mesh_stiffness_scale", r.covered_mesh},
                     {"preload_torque", r.covered_tp},
                     {"series_compliance", r.covered_compliance}};
  line["model_error_scale"] = {e.model_error_scale[0], e.model_error_scale[1],
                               e.model_error_scale[2]};
  return line;
}

/// The runs' totals for the summary.
struct Tally {
  int covered_mesh = 0, covered_tp = 0, covered_compliance = 0, flags_right = 0;
  double worst_mesh = 0.0, worst_tp = 0.0, worst_compliance = 0.0;
  /// Sums of (error / std)^2: 1 per run on average if the stds are right.
  double z2_mesh = 0.0, z2_tp = 0.0, z2_compliance = 0.0;
  std::vector<double> errors_mesh, errors_tp, errors_compliance;  ///< |relative error| per run
  double worst_drift = 0.0;  ///< [sigmas at the dwell's start] the largest move over the dwell
  int drifted = 0;           ///< runs with a move beyond 1 sigma

  void add(const CalibrationEstimate& e, const CalibrationVector& p, double compliance,
           const RunErrors& r) {
    worst_mesh = std::max(worst_mesh, std::abs(r.mesh));
    worst_tp = std::max(worst_tp, std::abs(r.tp));
    worst_compliance = std::max(worst_compliance, std::abs(r.compliance));
    errors_mesh.push_back(std::abs(r.mesh));
    errors_tp.push_back(std::abs(r.tp));
    errors_compliance.push_back(std::abs(r.compliance));
    covered_mesh += r.covered_mesh;
    covered_tp += r.covered_tp;
    covered_compliance += r.covered_compliance;
    auto z2 = [](double error, double std) { return error * error / std::max(std * std, 1e-300); };
    z2_mesh += z2(e.value[kMeshScale] - p[kMeshScale], e.std[kMeshScale]);
    z2_tp += z2(e.value[kPreloadTorque] - p[kPreloadTorque], e.std[kPreloadTorque]);
    z2_compliance += z2(e.series_compliance - compliance, e.series_compliance_std);
    flags_right += r.flags_right;
  }

  nlohmann::json summary(const MonteCarloArgs& a) const {
    nlohmann::json summary;
    summary["runs"] = a.runs;
    summary["worst_error"] = {{"mesh_stiffness_scale", worst_mesh},
                              {"preload_torque", worst_tp},
                              {"series_compliance", worst_compliance}};
    summary["median_error"] = {{"mesh_stiffness_scale", median(errors_mesh)},
                               {"preload_torque", median(errors_tp)},
                               {"series_compliance", median(errors_compliance)}};
    summary["covered"] = {{"mesh_stiffness_scale", covered_mesh},
                          {"preload_torque", covered_tp},
                          {"series_compliance", covered_compliance}};
    summary["identification_flags_right"] = flags_right;
    const double n = std::max(1, a.runs);
    summary["rms_error_over_std"] = {{"mesh_stiffness_scale", std::sqrt(z2_mesh / n)},
                                     {"preload_torque", std::sqrt(z2_tp / n)},
                                     {"series_compliance", std::sqrt(z2_compliance / n)}};
    if (a.dwell > 0.0)
      summary["dwell"] = {{"seconds", a.dwell},
                          {"torque", a.dwell_torque},
                          {"worst_sigmas", worst_drift},
                          {"runs_beyond_1_sigma", drifted}};
    return summary;
  }
};

/// One run: draws the true rig, records its load_sweep, replays it through the nominal pipeline,
/// prints the run's line and adds it to the tally.
void monteCarloRun(const MonteCarloArgs& a, const RigConfig& nominal, int run,
                   std::mt19937_64& draw, std::uniform_real_distribution<double>& uni,
                   Tally& tally) {
  const RigConfig truth = drawTruth(nominal, draw, uni);
  LoadSweepSpec spec;
  spec.seed = a.seed + static_cast<std::uint64_t>(run);
  spec.speed_rpm = a.speed;
  spec.dwell = a.dwell;
  spec.dwell_torque = a.dwell_torque;
  const LoadSweep sweep = makeLoadSweep(truth, spec);

  PipelineOptions options;
  options.dynamics = false;  // the calibration needs the readings and the torque, not the dynamics
  RigPipeline pipeline(nominal, options);
  WindowLog sink;
  sink.enabled = a.windows;
  CalibrationEstimate before_dwell;
  replay(sweep, pipeline, sink, a.dwell > 0.0 ? sweep.truth.levels.back().t0 : -1.0, &before_dwell);
  const CalibrationEstimate& e = pipeline.calibrator()->estimate();

  const CalibrationVector p = sweep.truth.parameters();
  const double compliance = trueCompliance(truth, p, nominal.calibration.reference_torque);
  const RunErrors r = runErrors(e, p, compliance);
  tally.add(e, p, compliance, r);
  nlohmann::json line = runLine(run, p, e, compliance, r);
  if (a.dwell > 0.0) {
    double run_worst = 0.0;
    line["dwell"] = dwellDrift(e, before_dwell, run_worst);
    tally.worst_drift = std::max(tally.worst_drift, run_worst);
    tally.drifted += run_worst > 1.0;
  }
  line["windows"] = e.windows;
  line["updates"] = e.updates;
  line["gated"] = e.gated;
  line["not_excited"] = e.not_excited;
  std::cout << line.dump() << std::endl;
}

}  // namespace
}  // namespace drivetrain_stiffness

int main(int argc, char** argv) {
  using namespace drivetrain_stiffness;
  CLI::App app{
      "Monte Carlo of the live calibration over load_sweep recordings of rigs with known truth"};
  MonteCarloArgs a;
  app.add_option("--config", a.config,
                 "Nominal gearbox YAML (its calibration block, or the defaults)");
  app.add_option("--runs", a.runs, "Number of rigs")->check(CLI::Range(1, 100000));
  app.add_option("--seed", a.seed, "Seed of the draws (each run's recording uses seed + run)");
  app.add_option("--speed-rpm", a.speed, "[rpm] pinion speed of the sweeps");
  app.add_flag("--windows", a.windows, "Print every closed window too");
  app.add_option("--dwell", a.dwell,
                 "[s] after the sweep, a hold at --dwell-torque: the estimate's drift over it "
                 "(docs/calibration.md)");
  app.add_option("--dwell-torque", a.dwell_torque, "[N*m] the dwell's pinion torque (3)");
  CLI11_PARSE(app, argc, argv);
  try {
    const RigConfig nominal = withCalibration(loadRigFile(a.config));
    std::mt19937_64 draw(a.seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    Tally tally;
    for (int run = 0; run < a.runs; ++run) monteCarloRun(a, nominal, run, draw, uni, tally);
    std::cout << nlohmann::json{{"summary", tally.summary(a)}}.dump() << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "drivetrain_calibration_mc: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

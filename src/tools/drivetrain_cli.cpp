// drivetrain_cli: the core models from the command line, JSON on stdout, errors on stderr with a
// non-zero exit code. No ROS needed.
//   drivetrain_cli bearing --config FILE [--fr N] [--fa N] [--moment N·m] [--tilt free|constrained] [--preload N]
//                          [--inner-interference m] [--outer-interference m]
//   drivetrain_cli mesh --config FILE [--model potential_energy|kuang_yang|iso6336] [--samples N] [--torque N·m]
//   drivetrain_cli modes --config FILE [--torque N·m] [--preload N]
//   drivetrain_cli sweep --config FILE [--start Hz] [--stop Hz] [--step Hz] [--amplitude N·m] [--fidelity F]
//                        [--direction up|down|both] [--out CSV]
//   drivetrain_cli simulate --config FILE --scene NAME [--method dopri5|rk4|trapezoidal|exponential|quasi_static|
//                           linear_modal|auto] [--error-bound E] [--step S] [--duration S] [--rtol R] [--out CSV]
//   drivetrain_cli study NAME --config FILE --out DIR [--no-png] [--plot-script PY]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <optional>

#include "drivetrain_stiffness/config/json_report.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"
#include "drivetrain_stiffness/studies/parameter_studies.hpp"
#include "study_command.hpp"

namespace ds = drivetrain_stiffness;

namespace {

struct BearingArgs {
  std::string config;
  double fr = 0.0, fa = 0.0, moment = 0.0;
  std::optional<double> preload, inner_interference, outer_interference;
  std::optional<std::string> tilt;
};

int runBearing(const BearingArgs& args) {
  ds::BearingSupportConfig cfg = ds::loadBearingFile(args.config);
  if (args.preload) cfg.axial_preload = *args.preload;
  if (args.inner_interference) cfg.interference.inner = *args.inner_interference;
  if (args.outer_interference) cfg.interference.outer = *args.outer_interference;
  if (args.tilt) cfg.tilt = ds::parseTiltCondition("--tilt", *args.tilt);
  const ds::BearingSupport support(cfg.spec, cfg.arrangement, cfg.axial_preload, cfg.interference, cfg.tilt);
  // Radial load along +x (the file's radial_preload plus --fr), axial along +z, moment about y.
  ds::Vector5d load;
  load << cfg.radial_preload + args.fr, 0.0, args.fa, 0.0, args.moment;
  const ds::BearingSolution sol = support.solve(load);
  nlohmann::json secant = nullptr;
  if (load[ds::kUx] != 0.0) {
    ds::Vector5d unloaded = load;
    unloaded[ds::kUx] = 0.0;
    const ds::BearingSolution base = support.solve(unloaded);
    secant = load[ds::kUx] / (sol.displacement[ds::kUx] - base.displacement[ds::kUx]);
  }
  std::cout << ds::bearingSolutionJson(support, sol, secant).dump(2) << std::endl;
  return 0;
}

struct MeshArgs {
  std::string config;
  std::optional<std::string> model;
  int samples = 100;
  double torque = 0.0;
};

int runMesh(const MeshArgs& args) {
  ds::RigConfig rig = ds::loadGearFile(args.config);
  if (args.model) rig.mesh_model = ds::parseMeshStiffnessModel("--model", *args.model);
  if (args.samples < 1 || args.samples > 100000) ds::throwInvalid("--samples", args.samples, "must be in [1, 100000]");
  const ds::AntiBacklashMesh mesh(rig.gears, rig.anti_backlash, rig.mesh_model, rig.mesh_samples);
  const double force = ds::meshForce(rig.gears, 0, args.torque);  // pinion torque -> LOA force
  std::cout << ds::meshJson(mesh, args.samples, force).dump(2) << std::endl;
  return 0;
}

struct SimulateArgs {
  std::string config, scene, method = "dopri5";
  std::optional<double> step, duration;
  double rtol = 1e-8, error_bound = 1e-6;
  std::optional<std::string> out;
  std::optional<std::string> sweep;  // "start:stop:step" for the oscillator scenes
};

struct SignalStats {
  double sum2 = 0.0, peak = 0.0;
  long n = 0;
  void add(double v) { sum2 += v * v; peak = std::max(peak, std::abs(v)); ++n; }
  nlohmann::json json() const { return {{"rms", n ? std::sqrt(sum2 / n) : 0.0}, {"peak", peak}}; }
};

// Up- and down-sweep of the backlash oscillator (kahraman_singh), JSON with both branches.
int runSweep(const SimulateArgs& args) {
  double start = 0, stop = 0, step = 0;
  char c1 = 0, c2 = 0;
  std::istringstream in(*args.sweep);
  if (!(in >> start >> c1 >> stop >> c2 >> step) || c1 != ':' || c2 != ':' || !(step > 0) || !(stop > start) || start <= 0) {
    throw ds::InvalidInput("--sweep = '" + *args.sweep + "': expected start:stop:step with 0 < start < stop, step > 0");
  }
  if (args.scene != "kahraman_singh") throw ds::InvalidInput("--sweep: only for --scene kahraman_singh");
  std::vector<double> up;
  const long n = static_cast<long>(std::floor((stop - start) / step + 1e-9));
  for (long i = 0; i <= n; ++i) up.push_back(start + i * step);  // no accumulated rounding
  const std::vector<double> down(up.rbegin(), up.rend());
  const ds::OscillatorSweepSpec spec;
  auto branch = [](const std::vector<ds::SweepPoint>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const ds::SweepPoint& p : v)
      a.push_back({{"frequency", p.frequency}, {"peak_to_peak", p.peak_to_peak}, {"min_x", p.min_x}, {"max_x", p.max_x}, {"regime", p.regime}});
    return a;
  };
  const nlohmann::json out = {{"scene", args.scene}, {"units", "dimensionless"},
                              {"parameters", {{"zeta", spec.zeta}, {"mean_force", spec.mean_force}, {"te_force", spec.te_force},
                                              {"ripple", spec.ripple}, {"settle_periods", spec.settle}, {"measure_periods", spec.measure}}},
                              {"up", branch(ds::sweepOscillator(spec, up))}, {"down", branch(ds::sweepOscillator(spec, down))}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

int runSimulate(const SimulateArgs& args) {
  if (args.sweep) return runSweep(args);
  const ds::RigConfig rig = ds::loadRigFile(args.config);
  ds::Scene scene = ds::makeScene(args.scene, rig);
  if (args.duration) {
    ds::requirePositive("--duration", *args.duration);
    scene.duration = std::round(*args.duration / scene.output_interval) * scene.output_interval;
    scene.transient = std::min(scene.transient, 0.3 * scene.duration);
  }
  const bool reduced = args.method == "quasi_static" || args.method == "linear_modal";
  const bool automatic = args.method == "auto";
  const ds::IntegratorMethod method =
      reduced || automatic ? ds::IntegratorMethod::kDopri5 : ds::parseIntegratorMethod("--method", args.method);
  ds::IntegratorOptions o;
  o.step = args.step ? *args.step : scene.suggested_step;
  ds::requirePositive("--step", o.step);
  if (method == ds::IntegratorMethod::kRk4 || method == ds::IntegratorMethod::kTrapezoidal) {
    // Fixed steps: sample every whole number of steps and end on a step.
    scene.output_interval = o.step * std::max(1.0, std::round(scene.output_interval / o.step));
    scene.duration = o.step * std::max(1.0, std::round(scene.duration / o.step));
  }
  o.relative_tolerance = args.rtol;
  ds::requirePositive("--rtol", args.rtol);
  o.absolute_tolerance = scene.units == "SI" ? 1e-6 * args.rtol : 1e-2 * args.rtol;
  o.max_step = scene.units == "SI" ? 1e-4 : 0.1;
  if (scene.units != "SI") o.divergence_limit = 1e3;
  std::ofstream csv;
  if (args.out) {
    csv.open(*args.out);
    if (!csv) throw ds::InvalidInput("--out = '" + *args.out + "': cannot write");
    csv << "# scene " << scene.name << " (" << scene.units << "), method " << ds::toString(method) << "\n";
    csv << "t,x_p,x_g,x,delta,mesh_force,drive_flank_force,back_flank_force,k_drive,k_back,phase\n";
    csv.precision(10);
  }
  SignalStats delta, xp, xg, x;
  ds::IntegrationStats stats;
  const auto start = std::chrono::steady_clock::now();
  const ds::Observer observe = [&](double t, const ds::State6& y) {
    const ds::GearRotorForces f = scene.model->forces(t, y);
    if (t >= scene.transient) {
      delta.add(f.delta);
      xp.add(y[0]);
      xg.add(y[1]);
      x.add(y[2]);
    }
    if (csv.is_open()) {
      ds::MeshInstant m;
      scene.model->excitation().at(t, m);
      csv << t << ',' << y[0] << ',' << y[1] << ',' << y[2] << ',' << f.delta << ',' << f.mesh << ','
          << f.drive_flank << ',' << f.back_flank << ',' << m.k_drive << ',' << m.k_back << ',' << m.phase << '\n';
    }
  };
  nlohmann::json chosen = nullptr;
  if (reduced) {
    ds::integrateReduced(*scene.model, ds::parseFidelity("--method", args.method),
                         0.0, scene.initial, scene.duration, scene.output_interval, observe);
  } else if (automatic) {
    const double pilot = std::min(scene.duration, 40.0 * scene.output_interval);
    const ds::AutoChoice c = ds::chooseAutomatically(*scene.model, 0.0, scene.initial, scene.output_interval, pilot, args.error_bound);
    nlohmann::json pilots = nlohmann::json::object();
    for (const auto& e : c.pilot_errors) pilots[e.first] = std::isfinite(e.second) ? nlohmann::json(e.second) : nlohmann::json(nullptr);
    chosen = {{"fidelity", ds::toString(c.fidelity)}, {"method", ds::toString(c.method)},
              {"relative_tolerance", c.fidelity == ds::Fidelity::kFull && c.method == ds::IntegratorMethod::kDopri5 ? nlohmann::json(c.relative_tolerance) : nlohmann::json(nullptr)},
              {"error_bound", args.error_bound}, {"pilot_s", c.pilot_duration}, {"pilot_errors", pilots}, {"reason", c.reason}};
    ds::integrateChoice(*scene.model, c, 0.0, scene.initial, scene.duration, scene.output_interval, observe, &stats);
  } else {
    ds::integrate(*scene.model, method, o, 0.0, scene.initial, scene.duration, scene.output_interval, observe, &stats);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json out = {
      {"scene", scene.name}, {"description", scene.description}, {"units", scene.units},
      {"method", reduced || automatic ? args.method : std::string(ds::toString(method))},
      {"auto", chosen},
      {"step", method == ds::IntegratorMethod::kRk4 || method == ds::IntegratorMethod::kTrapezoidal ? nlohmann::json(o.step) : nlohmann::json(nullptr)},
      {"relative_tolerance", method == ds::IntegratorMethod::kDopri5 ? nlohmann::json(o.relative_tolerance) : nlohmann::json(nullptr)},
      {"sim_s", scene.duration}, {"wall_s", wall}, {"rtf", scene.duration / wall},
      {"steps", stats.steps}, {"rejected", stats.rejected}, {"rhs_evaluations", stats.rhs_evaluations}, {"events", stats.events},
      {"statistics_from", scene.transient},
      {"delta", delta.json()}, {"x_p", xp.json()}, {"x_g", xg.json()}, {"x", x.json()},
      {"csv", args.out ? nlohmann::json(*args.out) : nlohmann::json(nullptr)}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

struct ModesArgs {
  std::string config;
  double torque = 0.1;
  std::optional<double> preload;
};

// Modal analysis at the operating point: bearing stiffness from the bearing model at this torque
// and preload, mesh stiffness at its mean and at its single- and double-pair extremes.
int runModes(const ModesArgs& args) {
  ds::RigConfig rig = ds::loadRigFile(args.config);
  if (!rig.dynamics.present) throw ds::InvalidInput(args.config + ": modes needs a 'dynamics:' block (masses, inertias)");
  ds::requireFinite("--torque", args.torque);
  if (args.preload) {
    ds::requireNonNegative("--preload", *args.preload);
    for (auto& b : rig.bearings) b.axial_preload = *args.preload;
  }
  ds::StiffnessEstimator estimator(rig);
  estimator.setTorque(args.torque);
  const std::array<double, 2> kb = estimator.shaftRadialStiffness();
  const ds::AntiBacklashMesh& mesh = estimator.mesh();
  const double force = ds::meshForce(rig.gears, 0, args.torque);
  double k_min = INFINITY, k_max = 0.0;
  for (int i = 0; i < 1024; ++i) {
    const double k = mesh.at((i + 0.5) / 1024, force).composite;
    k_min = std::min(k_min, k);
    k_max = std::max(k_max, k);
  }
  const ds::GearRotorParameters p = ds::rigRotorParameters(rig, mesh, kb);
  auto modesJson = [&](double ks) {
    nlohmann::json list = nlohmann::json::array();
    for (const ds::Mode& m : ds::modalAnalysis(p, ks)) {
      list.push_back({{"natural_frequency_hz", m.natural_frequency}, {"damped_frequency_hz", m.damped_frequency},
                      {"damping_ratio", m.damping_ratio}, {"dominant_coordinate", m.dominant},
                      {"shape", {m.shape[0], m.shape[1], m.shape[2]}}});
    }
    return list;
  };
  nlohmann::json floquet_json = nullptr;
  if (rig.dynamics.bearing_clearance[0] == 0.0 && rig.dynamics.bearing_clearance[1] == 0.0) {
    ds::DynamicsEstimator dynamics(rig, kb, 1000.0);
    const auto& ex = dynamic_cast<const ds::RigExcitation&>(dynamics.model().excitation());
    dynamics.reset(0.0, args.torque);
    const ds::FloquetResult f = ds::floquet(dynamics.model(), dynamics.state(), 0.0, 1.0 / ex.meshFrequency());
    floquet_json = {{"max_multiplier_modulus", f.max_modulus}, {"margin", f.margin},
                    {"mesh_frequency_hz", ex.meshFrequency()}, {"stable", f.margin > 0.0}};
  }
  const nlohmann::json out = {
      {"masses", {{"pinion_mass", p.pinion_mass}, {"gear_mass", p.gear_mass}, {"equivalent_mass", p.equivalentMass()},
                  {"pinion_inertia", p.pinion_inertia}, {"gear_inertia", p.gear_inertia}}},
      {"stiffness", {{"pinion_bearing", kb[0]}, {"gear_bearing", kb[1]}, {"mesh_mean", ds::meanMeshStiffness(mesh)},
                     {"mesh_min", k_min}, {"mesh_max", k_max}}},
      {"damping", {{"mesh", p.mesh_damping}, {"pinion_bearing", p.bearing_damping[0]}, {"gear_bearing", p.bearing_damping[1]}}},
      {"torque", args.torque},
      {"modes", {{"mesh_mean", modesJson(ds::meanMeshStiffness(mesh))}, {"mesh_single_pair", modesJson(k_min)},
                 {"mesh_double_pair", modesJson(k_max)}}},
      {"floquet", floquet_json},
      {"units", "Hz, N/m, kg, kg m^2, N s/m"}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

struct SweepArgs {
  std::string config, fidelity = "full", direction = "up";
  ds::SweepSpec spec;
  std::optional<std::string> out;
};

// Frequency sweep of a sine torque fluctuation (seed 000 section 4.2): RMS per coordinate and
// the top three resonance peaks, refined below the step.
int runTorqueSweep(const SweepArgs& args) {
  const ds::RigConfig rig = ds::loadRigFile(args.config);
  ds::SweepSpec spec = args.spec;
  spec.fidelity = ds::parseFidelity("--fidelity", args.fidelity);
  spec.direction = ds::parseSweepDirection("--direction", args.direction);
  const ds::SweepOutput sweep = ds::torqueSweep(rig, spec);
  static const char* kNames[3] = {"x_p", "x_g", "x"};
  nlohmann::json coords = nlohmann::json::object();
  for (int c = 0; c < 3; ++c) {
    nlohmann::json peaks = nlohmann::json::array();
    for (const ds::SpectralPeak& p : sweep.peaks[c]) peaks.push_back({{"frequency_hz", p.frequency}, {"rms", p.amplitude}});
    nlohmann::json spectrum = nlohmann::json::array();
    for (const ds::SpectralPeak& p : sweep.spectrum_peaks[c])
      spectrum.push_back({{"frequency_hz", p.frequency}, {"amplitude", p.amplitude}});
    coords[kNames[c]] = {{"rms", sweep.rms[c]}, {"peaks", peaks}, {"spectrum_peaks", spectrum}};
    if (!sweep.rms_down[c].empty()) {
      // Largest up/down disagreement relative to the larger RMS: a jump (two branches) when large.
      double worst = 0.0;
      for (std::size_t i = 0; i < sweep.rms[c].size(); ++i) {
        const double a = sweep.rms[c][i], b = sweep.rms_down[c][i];
        if (std::max(a, b) > 0.0) worst = std::max(worst, std::abs(a - b) / std::max(a, b));
      }
      coords[kNames[c]]["rms_down"] = sweep.rms_down[c];
      coords[kNames[c]]["max_up_down_difference"] = worst;
    }
  }
  if (args.out) {
    std::ofstream csv(*args.out);
    if (!csv) throw ds::InvalidInput("--out = '" + *args.out + "': cannot write");
    const bool both = !sweep.rms_down[0].empty();
    csv << "frequency_hz,rms_x_p_m,rms_x_g_m,rms_x_m" << (both ? ",rms_down_x_p_m,rms_down_x_g_m,rms_down_x_m" : "") << '\n';
    for (std::size_t i = 0; i < sweep.frequency.size(); ++i) {
      csv << sweep.frequency[i] << ',' << sweep.rms[0][i] << ',' << sweep.rms[1][i] << ',' << sweep.rms[2][i];
      if (both) csv << ',' << sweep.rms_down[0][i] << ',' << sweep.rms_down[1][i] << ',' << sweep.rms_down[2][i];
      csv << '\n';
    }
  }
  const nlohmann::json out = {{"fidelity", args.fidelity}, {"frequency_hz", sweep.frequency}, {"coordinates", coords},
                              {"torque_amplitude", spec.torque_amplitude}, {"settle_s", spec.settle}, {"measure_s", spec.measure},
                              {"direction", ds::toString(spec.direction)}, {"sample_interval_s", sweep.sample_interval},
                              {"spectrum_resolution_hz", sweep.spectrum_resolution},
                              {"units", "Hz, m (RMS about the mean)"}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"drivetrain_stiffness command-line models (SI units, JSON output)"};
  app.require_subcommand(1);

  BearingArgs bearing;
  auto* cmd = app.add_subcommand("bearing", "quasi-static bearing equilibrium and stiffness");
  cmd->add_option("--config", bearing.config, "YAML file with a 'bearing:' block")->required();
  cmd->add_option("--fr", bearing.fr, "external radial load along +x [N] (added to radial_preload)");
  cmd->add_option("--fa", bearing.fa, "external axial load along +z [N] (added to a single bearing's preload)");
  cmd->add_option("--moment", bearing.moment, "tilting moment about y [N·m] (needs --tilt free)");
  cmd->add_option("--tilt", bearing.tilt, "constrained (default: shaft held in line, moment is a reaction) or free");
  cmd->add_option("--preload", bearing.preload, "axial preload [N], overrides the file");
  cmd->add_option("--inner-interference", bearing.inner_interference, "diametral inner-ring interference [m]");
  cmd->add_option("--outer-interference", bearing.outer_interference, "diametral outer-ring interference [m]");

  MeshArgs mesh;
  auto* mesh_cmd = app.add_subcommand("mesh", "involute geometry and (anti-backlash composite) mesh stiffness over one mesh period");
  mesh_cmd->add_option("--config", mesh.config, "YAML file with 'gears:' (and optionally 'anti_backlash:', 'mesh:')")->required();
  mesh_cmd->add_option("--model", mesh.model, "potential_energy (default), kuang_yang (unverified) or iso6336");
  mesh_cmd->add_option("--samples", mesh.samples, "phases printed over one mesh period (default 100)");
  mesh_cmd->add_option("--torque", mesh.torque, "pinion torque [N·m] setting the flank state (default 0)");

  SimulateArgs sim;
  auto* sim_cmd = app.add_subcommand("simulate", "integrate the 3-DOF transverse-torsional model on a named scene");
  sim_cmd->add_option("--config", sim.config, "gearbox YAML with gears, bearings and dynamics")->required();
  sim_cmd->add_option("--scene", sim.scene, "nominal, torque_steps, low_preload, bearing_rattle, near_rigid_bearings, "
                                            "parametric_resonance, kahraman_singh, chaotic, run_up, speed_steps, reverse")->required();
  sim_cmd->add_option("--method", sim.method, "dopri5 (default, adaptive with events), rk4, trapezoidal, exponential "
                                              "(exact in the linear regime), quasi_static, linear_modal, auto");
  sim_cmd->add_option("--error-bound", sim.error_bound, "auto: relative RMS error of delta to meet (default 1e-6)");
  sim_cmd->add_option("--step", sim.step, "fixed step [s] for rk4/trapezoidal (default: the scene's, 20 per stiffest period)");
  sim_cmd->add_option("--duration", sim.duration, "simulated time [s] (default: the scene's)");
  sim_cmd->add_option("--rtol", sim.rtol, "dopri5 relative tolerance (default 1e-8)");
  sim_cmd->add_option("--out", sim.out, "write the time series to this CSV file");
  sim_cmd->add_option("--sweep", sim.sweep, "kahraman_singh only: up- and down-sweep start:stop:step of the frequency W");

  ModesArgs modes;
  auto* modes_cmd = app.add_subcommand("modes", "natural and damped frequencies, damping ratios, mode shapes, Floquet margin");
  modes_cmd->add_option("--config", modes.config, "gearbox YAML with gears, bearings and dynamics")->required();
  modes_cmd->add_option("--torque", modes.torque, "pinion torque [N·m] (default 0.1)");
  modes_cmd->add_option("--preload", modes.preload, "axial preload of every bearing [N], overrides the file");

  SweepArgs sweep;
  auto* sweep_cmd = app.add_subcommand("sweep", "frequency sweep of a sine torque fluctuation: RMS and resonance peaks");
  sweep_cmd->add_option("--config", sweep.config, "gearbox YAML with gears, bearings and dynamics")->required();
  sweep_cmd->add_option("--start", sweep.spec.start, "first frequency [Hz] (default 60)");
  sweep_cmd->add_option("--stop", sweep.spec.stop, "last frequency [Hz] (default 3000: seed 000 section 4.2)");
  sweep_cmd->add_option("--step", sweep.spec.step, "frequency step [Hz] (default 60)");
  sweep_cmd->add_option("--amplitude", sweep.spec.torque_amplitude, "torque fluctuation amplitude [N·m] (default 0.05)");
  sweep_cmd->add_option("--fidelity", sweep.fidelity, "full (dopri5, default), linear_modal or quasi_static");
  sweep_cmd->add_option("--direction", sweep.direction, "up (default), down, or both (up then down, for jumps)");
  sweep_cmd->add_option("--out", sweep.out, "write frequency and RMS per coordinate to this CSV");

  ds::StudyArgs study;
  study.plot_script = DRIVETRAIN_PLOT_STUDY_SCRIPT;
  auto* study_cmd = app.add_subcommand("study", "a seed 000 parameter study (Figs 4, 5, 9, 10, 11) to CSV and PNG");
  study_cmd->add_option("name", study.name, "bearing_shrink, bearing_preload, rms_sweep, resonance_shrink or resonance_preload")
      ->required()->check(CLI::IsMember(ds::studyNames()));
  study_cmd->add_option("--config", study.config, "gearbox YAML with gears, bearings and dynamics")->required();
  study_cmd->add_option("--out", study.out, "output directory (created if missing)")->required();
  study_cmd->add_flag("!--no-png", study.png, "write the CSV only");
  study_cmd->add_option("--plot-script", study.plot_script, "matplotlib script: SCRIPT CSV PNG");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (app.got_subcommand(cmd)) return runBearing(bearing);
    if (app.got_subcommand(mesh_cmd)) return runMesh(mesh);
    if (app.got_subcommand(sim_cmd)) return runSimulate(sim);
    if (app.got_subcommand(modes_cmd)) return runModes(modes);
    if (app.got_subcommand(sweep_cmd)) return runTorqueSweep(sweep);
    if (app.got_subcommand(study_cmd)) return ds::runStudyCommand(study);
  } catch (const ds::InvalidInput& e) {
    std::cerr << "drivetrain_cli: invalid input: " << e.what() << std::endl;
    return 2;
  } catch (const ds::UnreachableLoad& e) {
    std::cerr << "drivetrain_cli: no equilibrium: " << e.what() << std::endl;
    return 3;
  } catch (const ds::UnstableIntegration& e) {
    std::cerr << "drivetrain_cli: unstable: " << e.what() << std::endl;
    return 4;
  }
  return 1;
}

// `drivetrain_cli simulate`: the 3-DOF model on a named scene (scenes.hpp) with any integrator or
// reduced fidelity, or `auto` (reduced_models.hpp); JSON summary of the run and, with --out, the
// time series as CSV. --sweep: the backlash oscillator's up- and down-sweep (oscillator_sweep.cpp).
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "simulate_options.hpp"
#include "subcommand.hpp"

namespace drivetrain_stiffness::cli {
namespace {

/// RMS and peak of |v| over the samples added.
struct SignalStats {
  double sum2 = 0.0, peak = 0.0;
  long n = 0;
  void add(double v) {
    sum2 += v * v;
    peak = std::max(peak, std::abs(v));
    ++n;
  }
  nlohmann::json json() const { return {{"rms", n ? std::sqrt(sum2 / n) : 0.0}, {"peak", peak}}; }
};

/// The scene shortened to --duration (whole output intervals), its transient at most 30 % of it.
void applyDuration(const SimulateArgs& args, Scene& scene) {
  if (args.duration) {
    requirePositive("--duration", *args.duration);
    scene.duration = std::round(*args.duration / scene.output_interval) * scene.output_interval;
    scene.transient = std::min(scene.transient, 0.3 * scene.duration);
  }
}

bool fixedStep(IntegratorMethod method) {
  return method == IntegratorMethod::kRk4 || method == IntegratorMethod::kTrapezoidal;
}

/// The integrator's options from --step and --rtol in the scene's units; a fixed-step method
/// samples every whole number of steps and ends on a step (the scene is adjusted). Throws
/// InvalidInput naming --step or --rtol.
IntegratorOptions integratorOptions(const SimulateArgs& args, IntegratorMethod method,
                                    Scene& scene) {
  IntegratorOptions o;
  o.step = args.step ? *args.step : scene.suggested_step;
  requirePositive("--step", o.step);
  if (fixedStep(method)) {
    scene.output_interval = o.step * std::max(1.0, std::round(scene.output_interval / o.step));
    scene.duration = o.step * std::max(1.0, std::round(scene.duration / o.step));
  }
  o.relative_tolerance = args.rtol;
  requirePositive("--rtol", args.rtol);
  const IntegratorScale scale = scene.scale();
  o.absolute_tolerance = scale.displacement * args.rtol;
  o.max_step = scale.max_step;
  o.divergence_limit = scale.divergence_limit;
  return o;
}

/// Opens --out with its comment and header lines. Throws InvalidInput if it cannot be written.
void openCsv(const std::string& path, const Scene& scene, IntegratorMethod method,
             std::ofstream& csv) {
  csv.open(path);
  if (!csv) throw InvalidInput("--out = '" + path + "': cannot write");
  csv << "# scene " << scene.name << " (" << scene.units << "), method " << toString(method)
      << "\n";
  csv << "t,x_p,x_g,x,delta,mesh_force,drive_flank_force,back_flank_force,k_drive,k_back,phase\n";
  csv.precision(10);
}

/// What a run observed: the statistics after the transient and the integrator's counts.
struct SimulationRecord {
  SignalStats delta, xp, xg, x;
  IntegrationStats stats;
};

/// `auto`: chooses the method on a pilot run, then runs it. Returns the choice as JSON.
nlohmann::json runAutomatically(const SimulateArgs& args, const Scene& scene,
                                const Observer& observe, IntegrationStats& stats) {
  // The run's length weighs the exponential method's set-up against dopri5's work.
  const double pilot = defaultPilotDuration(scene.duration, scene.output_interval);
  const AutoChoice c = chooseAutomatically(*scene.model, 0.0, scene.initial, scene.output_interval,
                                           pilot, args.error_bound, scene.duration, scene.scale());
  nlohmann::json pilots = nlohmann::json::object();
  for (const auto& e : c.pilot_errors)
    pilots[e.first] = std::isfinite(e.second) ? nlohmann::json(e.second) : nlohmann::json(nullptr);
  nlohmann::json chosen = {
      {"fidelity", toString(c.fidelity)},
      {"method", toString(c.method)},
      {"relative_tolerance", c.fidelity == Fidelity::kFull && c.method == IntegratorMethod::kDopri5
                                 ? nlohmann::json(c.relative_tolerance)
                                 : nlohmann::json(nullptr)},
      {"error_bound", args.error_bound},
      {"pilot_s", c.pilot_duration},
      {"pilot_errors", pilots},
      {"reason", c.reason}};
  integrateChoice(*scene.model, c, 0.0, scene.initial, scene.duration, scene.output_interval,
                  observe, &stats);
  return chosen;
}

/// The run's JSON summary.
nlohmann::json simulationSummary(const SimulateArgs& args, const Scene& scene,
                                 IntegratorMethod method, bool named_by_args,
                                 const IntegratorOptions& o, const nlohmann::json& chosen,
                                 const SimulationRecord& r, double wall) {
  return {{"scene", scene.name},
          {"description", scene.description},
          {"units", scene.units},
          {"method", named_by_args ? args.method : std::string(toString(method))},
          {"auto", chosen},
          {"step", fixedStep(method) ? nlohmann::json(o.step) : nlohmann::json(nullptr)},
          {"relative_tolerance", method == IntegratorMethod::kDopri5
                                     ? nlohmann::json(o.relative_tolerance)
                                     : nlohmann::json(nullptr)},
          {"sim_s", scene.duration},
          {"wall_s", wall},
          {"rtf", scene.duration / wall},
          {"steps", r.stats.steps},
          {"rejected", r.stats.rejected},
          {"rhs_evaluations", r.stats.rhs_evaluations},
          {"events", r.stats.events},
          {"statistics_from", scene.transient},
          {"delta", r.delta.json()},
          {"x_p", r.xp.json()},
          {"x_g", r.xg.json()},
          {"x", r.x.json()},
          {"csv", args.out ? nlohmann::json(*args.out) : nlohmann::json(nullptr)}};
}

int runSimulate(const SimulateArgs& args) {
  if (args.sweep) return runOscillatorSweep(args);
  const RigConfig rig = loadRigFile(args.config);
  Scene scene = makeScene(args.scene, rig);
  applyDuration(args, scene);
  const bool reduced = args.method == "quasi_static" || args.method == "linear_modal";
  const bool automatic = args.method == "auto";
  const IntegratorMethod method = reduced || automatic
                                      ? IntegratorMethod::kDopri5
                                      : parseIntegratorMethod("--method", args.method);
  const IntegratorOptions o = integratorOptions(args, method, scene);
  std::ofstream csv;
  if (args.out) openCsv(*args.out, scene, method, csv);
  SimulationRecord r;
  const auto start = std::chrono::steady_clock::now();
  const Observer observe = [&](double t, const State6& y) {
    const GearRotorForces f = scene.model->forces(t, y);
    if (t >= scene.transient) {
      r.delta.add(f.delta);
      r.xp.add(y[0]);
      r.xg.add(y[1]);
      r.x.add(y[2]);
    }
    if (csv.is_open()) {
      MeshInstant m;
      scene.model->excitation().at(t, m);
      csv << t << ',' << y[0] << ',' << y[1] << ',' << y[2] << ',' << f.delta << ',' << f.mesh
          << ',' << f.drive_flank << ',' << f.back_flank << ',' << m.k_drive << ',' << m.k_back
          << ',' << m.phase << '\n';
    }
  };
  nlohmann::json chosen = nullptr;
  if (reduced) {
    integrateReduced(*scene.model, parseFidelity("--method", args.method), 0.0, scene.initial,
                     scene.duration, scene.output_interval, observe);
  } else if (automatic) {
    chosen = runAutomatically(args, scene, observe, r.stats);
  } else {
    integrate(*scene.model, method, o, 0.0, scene.initial, scene.duration, scene.output_interval,
              observe, &r.stats);
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout
      << simulationSummary(args, scene, method, reduced || automatic, o, chosen, r, wall).dump(2)
      << std::endl;
  return 0;
}

}  // namespace

Subcommand addSimulateCommand(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "simulate", "integrate the 3-DOF transverse-torsional model on a named scene");
  cmd->add_option("--config", args->config, "gearbox YAML with gears, bearings and dynamics")
      ->required();
  cmd->add_option("--scene", args->scene,
                  "nominal, torque_steps, low_preload, bearing_rattle, near_rigid_bearings, "
                  "parametric_resonance, kahraman_singh, chaotic, run_up, speed_steps, reverse")
      ->required();
  cmd->add_option("--method", args->method,
                  "dopri5 (default, adaptive with events), rk4, trapezoidal, exponential "
                  "(exact in the linear regime), quasi_static, linear_modal, auto");
  cmd->add_option("--error-bound", args->error_bound,
                  "auto: relative RMS error of delta to meet (default 1e-6)");
  cmd->add_option(
      "--step", args->step,
      "fixed step [s] for rk4/trapezoidal (default: the scene's, 20 per stiffest period)");
  cmd->add_option("--duration", args->duration, "simulated time [s] (default: the scene's)");
  cmd->add_option("--rtol", args->rtol, "dopri5 relative tolerance (default 1e-8)");
  cmd->add_option("--out", args->out, "write the time series to this CSV file");
  cmd->add_option("--sweep", args->sweep,
                  "kahraman_singh only: up- and down-sweep start:stop:step of the frequency W");
  return {cmd, [args] { return runSimulate(*args); }};
}

}  // namespace drivetrain_stiffness::cli

// drivetrain_bench: speed against error for every method on every scene, side by side with the
// peers a user would otherwise pick (Boost.odeint, SUNDIALS CVODE). For each scene a
// tight-tolerance dopri5 run (rtol 1e-12) is the reference; every other run reports
//   {scene, method, setting, step, wall_s, sim_s, rtf, err_rms_rel, steps}
// as one JSON line (the exact propagators add setup_s, rtf_with_setup and rtf_with_setup_1s; on
// the scenes whose speed changes, sliced_exact is the exact propagation at any speed), err_rms_rel
// = RMS(delta - delta_ref) / RMS(delta_ref) over the samples after the scene's transient. With
// --plot it also writes one PNG of error against real-time factor per scene (scripts/plot_bench.py,
// matplotlib).
//   drivetrain_bench [--config FILE] [--scenes a,b,...] [--out DIR] [--plot] [--quick]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"
#include "peer_integrators.hpp"

namespace ds = drivetrain_stiffness;

namespace {

std::string fmt(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

struct Samples {
  std::vector<double> t;
  std::vector<ds::State6> y;
};

struct Timed {
  double wall = 0.0;
  long steps = 0;
  Samples samples;
};

// Runs `fn` (which fills samples and returns steps) until 0.05 s or 3 repeats; keeps the best wall
// time. The samples' storage is reserved for `expected` samples before the clock starts, so that
// the time is the method's and not the recording's (growing the two vectors sample by sample costs
// up to a third of a short run).
template <typename F>
Timed timed(std::size_t expected, F fn) {
  Timed best;
  best.wall = INFINITY;
  double total = 0.0;
  for (int rep = 0; rep < 3 && total < 0.05; ++rep) {
    Samples s;
    s.t.reserve(expected);
    s.y.reserve(expected);
    const auto start = std::chrono::steady_clock::now();
    const long steps = fn(s);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    total += wall;
    if (wall < best.wall) best = Timed{wall, steps, std::move(s)};
  }
  return best;
}

std::vector<double> deltas(const ds::Scene& scene, const Samples& s) {
  std::vector<double> d;
  for (std::size_t i = 0; i < s.t.size(); ++i) {
    if (s.t[i] >= scene.transient) d.push_back(scene.model->forces(s.t[i], s.y[i]).delta);
  }
  return d;
}

double rmsError(const std::vector<double>& d, const std::vector<double>& ref) {
  if (d.size() != ref.size() || ref.empty()) return NAN;
  double e = 0.0, r = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    e += (d[i] - ref[i]) * (d[i] - ref[i]);
    r += ref[i] * ref[i];
  }
  return std::sqrt(e / r);
}

/// Records a run's output samples into `s`.
auto record(Samples& s) {
  return [&s](double t, const ds::State6& y) {
    s.t.push_back(t);
    s.y.push_back(y);
  };
}

/// One scene's runs: the reference, then every method and peer, each reported as a JSON line to
/// stdout and to `file`.
class SceneBench {
 public:
  SceneBench(const std::string& name, const ds::RigConfig& rig, bool quick, std::ofstream& file)
      : name_(name), quick_(quick), file_(file), scene_(makeBenchScene(name, rig, quick)) {
    // Output samples of a run: one per interval and the first, with one to spare.
    expected_ = static_cast<std::size_t>(std::ceil(scene_.duration / scene_.output_interval)) + 2;
    scale_ = scene_.scale();
    abs_per_rel_ = scale_.displacement;  // ~1 um (SI) or a hundredth of the unit gap
    ref_opt_.relative_tolerance = 1e-12;
    ref_opt_.absolute_tolerance = 1e-12 * abs_per_rel_;
    ref_opt_.max_step = scale_.max_step;
    ref_opt_.divergence_limit = scale_.divergence_limit;
    Samples ref_samples;
    ds::integrate(*scene_.model, ds::IntegratorMethod::kDopri5, ref_opt_, 0.0, scene_.initial,
                  scene_.duration, scene_.output_interval, record(ref_samples));
    ref_ = deltas(scene_, ref_samples);
    fallback_ = ref_opt_;
    fallback_.relative_tolerance = 1e-9;
    fallback_.absolute_tolerance = 1e-9 * abs_per_rel_;
  }

  void run() {
    runExponential();
    if (scene_.motion) runSlicedExact();
    runReduced();
    for (double bound : {1e-2, 1e-6}) runAuto(bound);
    runOurs();
    runPeers();
  }

 private:
  static ds::Scene makeBenchScene(const std::string& name, const ds::RigConfig& rig, bool quick) {
    const std::vector<std::string> moving = ds::motionSceneNames();
    const bool motion_scene = std::find(moving.begin(), moving.end(), name) != moving.end();
    return ds::makeScene(name, rig, motion_scene ? (quick ? 0.05 : 0.5) : 0.0);
  }

  void emit(const nlohmann::json& j) {
    std::cout << j.dump() << std::endl;
    file_ << j.dump() << "\n";
  }

  nlohmann::json errorJson(const Timed& r) const {
    const double err = rmsError(deltas(scene_, r.samples), ref_);
    return name_ == "chaotic" || !std::isfinite(err) ? nlohmann::json(nullptr)
                                                     : nlohmann::json(err);
  }

  void report(const std::string& method, const std::string& setting, double step, const Timed& r,
              const std::string& error) {
    nlohmann::json j = {{"scene", name_},
                        {"method", method},
                        {"setting", setting},
                        {"step", step > 0 ? nlohmann::json(step) : nlohmann::json(nullptr)},
                        {"sim_s", scene_.duration},
                        {"units", scene_.units}};
    if (!error.empty()) {
      j["error"] = error;
    } else {
      j["wall_s"] = r.wall;
      j["rtf"] = scene_.duration / r.wall;
      j["err_rms_rel"] = errorJson(r);
      j["steps"] = r.steps;
    }
    emit(j);
  }

  // The exact propagators: built once per parameter set (setup_s, timed here) and then streamed
  // (wall_s). rtf is the streaming rate; rtf_with_setup charges the setup to this run,
  // rtf_with_setup_1s to one second of model time at this streaming rate (the scenes differ in
  // length).
  void reportExact(const std::string& method, const std::string& setting, double setup,
                   const Timed& r, const nlohmann::json& extra) {
    nlohmann::json j = {{"scene", name_},
                        {"method", method},
                        {"setting", setting},
                        {"step", nullptr},
                        {"sim_s", scene_.duration},
                        {"units", scene_.units},
                        {"wall_s", r.wall},
                        {"setup_s", setup},
                        {"rtf", scene_.duration / r.wall},
                        {"rtf_with_setup", scene_.duration / (r.wall + setup)},
                        {"rtf_with_setup_1s", 1.0 / (r.wall / scene_.duration + setup)},
                        {"steps", r.steps}};
    j.update(extra);
    j["err_rms_rel"] = errorJson(r);
    emit(j);
  }

  void ours(ds::IntegratorMethod m, const ds::IntegratorOptions& o, const std::string& setting) {
    const double step = m == ds::IntegratorMethod::kDopri5 ? 0.0 : o.step;
    try {
      const Timed r = timed(expected_, [&](Samples& s) {
        ds::IntegrationStats st;
        ds::integrate(*scene_.model, m, o, 0.0, scene_.initial, scene_.duration,
                      scene_.output_interval, record(s), &st);
        return st.steps;
      });
      report(ds::toString(m), setting, step, r, "");
    } catch (const std::exception& e) {
      report(ds::toString(m), setting, step, Timed{}, e.what());
    }
  }

  template <typename Fn>
  void peer(const std::string& label, double rtol, Fn fn) {
    try {
      const Timed r = timed(expected_, [&](Samples& s) {
        return fn(*scene_.model, scene_.initial, scene_.duration, scene_.output_interval, rtol,
                  rtol * abs_per_rel_, record(s))
            .steps;
      });
      report(label, "rtol=" + fmt(rtol), 0.0, r, "");
    } catch (const std::exception& e) {
      report(label, "rtol=" + fmt(rtol), 0.0, Timed{}, e.what());
    }
  }

  /// Exact exponential (a constant speed: periodic propagators per output interval).
  void runExponential() {
    for (double factor : quick_ ? std::vector<double>{1.0}
                                : std::vector<double>{32.0, 16.0, 8.0, 4.0, 2.0, 1.0, 0.5}) {
      const std::string setting = "magnus step " + fmt(factor) + "/omega_max";
      try {
        const auto start = std::chrono::steady_clock::now();
        const ds::PeriodicExponentialPropagator propagator(*scene_.model, 0.0,
                                                           scene_.output_interval, factor);
        const double setup =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        long fallbacks = 0;
        const Timed r = timed(expected_, [&](Samples& s) {
          ds::IntegrationStats st;
          propagator.run(scene_.initial, scene_.duration, record(s), fallback_, &st);
          fallbacks = st.fallbacks;
          return st.steps;
        });
        reportExact(
            "exponential", setting, setup, r,
            {{"magnus_steps_per_period", propagator.magnusSteps()}, {"fallbacks", fallbacks}});
      } catch (const std::exception& e) {
        report("exponential", setting, 0.0, Timed{}, e.what());
      }
    }
  }

  // Exact propagation at any speed (the scenes whose speed changes): SlicedModalPropagator along
  // the scene's readings, as the node follows the encoders (propagateMotionScene), built fresh
  // for sliced_exact and for auto along a measured motion. Its setup is one eigen-decomposition
  // per slice, made for sliced_exact by crossing every slice once; steps = slices crossed.
  std::unique_ptr<const ds::SlicedModalPropagator> makeSliced() const {
    return std::make_unique<const ds::SlicedModalPropagator>(
        scene_.model->parameters(), scene_.motion->slices, scene_.motion->te_amplitude,
        scene_.motion->backlash);
  }
  long runSliced(const ds::SlicedModalPropagator& exact, Samples& s, long* fallbacks) const {
    ds::IntegrationStats st;
    ds::propagateMotionScene(scene_, exact, fallback_, record(s), &st);
    if (fallbacks) *fallbacks = st.fallbacks;
    return st.steps;
  }

  void runSlicedExact() {
    const ds::SceneMotion& motion = *scene_.motion;
    const std::string setting = std::to_string(motion.slices->size()) + " slices, readings every " +
                                fmt(motion.reading_interval) + " s";
    try {
      const auto start = std::chrono::steady_clock::now();
      const auto exact = makeSliced();
      ds::State6 y = scene_.initial;
      double phase = motion.phase[0];
      const double f = 1.0;  // [Hz] one mesh period in 1 s: every slice crossed once
      if (!exact->propagate(y, phase, f, 1.0 / f, motion.drive_force)) {
        throw std::runtime_error("left the linear regime while crossing the slices at 1 Hz");
      }
      const double setup =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const long decompositions = exact->decompositions();
      long fallbacks = 0;
      const Timed r =
          timed(expected_, [&](Samples& s) { return runSliced(*exact, s, &fallbacks); });
      reportExact("sliced_exact", setting, setup, r,
                  {{"fallbacks", fallbacks},
                   {"decompositions", decompositions},
                   {"slices_per_period", motion.slices->size()}});
    } catch (const std::exception& e) {
      report("sliced_exact", setting, 0.0, Timed{}, e.what());
    }
  }

  /// Reduced fidelities (rig scenes only): model only what the scene needs.
  void runReduced() {
    for (ds::Fidelity f : {ds::Fidelity::kQuasiStatic, ds::Fidelity::kLinearModal}) {
      try {
        const Timed r = timed(expected_, [&](Samples& s) {
          ds::integrateReduced(*scene_.model, f, 0.0, scene_.initial, scene_.duration,
                               scene_.output_interval, record(s));
          return std::lround(scene_.duration / scene_.output_interval);
        });
        report(ds::toString(f), "reduced model", 0.0, r, "");
      } catch (const std::exception& e) {
        report(ds::toString(f), "reduced model", 0.0, Timed{}, e.what());
      }
    }
  }

  // auto at an error bound; the wall time includes the pilot runs that made the choice. Along a
  // measured motion (the scenes whose speed changes) the exact method is the sliced one, and this
  // bench's reduced fidelities (integrateReduced) run at a constant speed only, so auto is the
  // sliced propagation, as the node runs it, set-up (every slice decomposed) included.
  void runAuto(double bound) {
    if (scene_.motion) {
      try {
        const Timed r =
            timed(expected_, [&](Samples& s) { return runSliced(*makeSliced(), s, nullptr); });
        report("auto",
               "bound=" + fmt(bound) + " -> sliced_exact (measured motion, set-up included)", 0.0,
               r, "");
      } catch (const std::exception& e) {
        report("auto", "bound=" + fmt(bound), 0.0, Timed{}, e.what());
      }
      return;
    }
    try {
      ds::AutoChoice chosen;
      const Timed r = timed(expected_, [&](Samples& s) {
        const double pilot = ds::defaultPilotDuration(scene_.duration, scene_.output_interval);
        chosen = ds::chooseAutomatically(*scene_.model, 0.0, scene_.initial, scene_.output_interval,
                                         pilot, bound, scene_.duration, scale_);
        ds::IntegrationStats st;
        ds::integrateChoice(*scene_.model, chosen, 0.0, scene_.initial, scene_.duration,
                            scene_.output_interval, record(s), &st);
        return st.steps;
      });
      report("auto",
             "bound=" + fmt(bound) + " -> " + ds::toString(chosen.fidelity) + "/" +
                 ds::toString(chosen.method),
             0.0, r, "");
    } catch (const std::exception& e) {
      report("auto", "bound=" + fmt(bound), 0.0, Timed{}, e.what());
    }
  }

  /// dopri5 at several tolerances, rk4 and trapezoidal at fractions of the suggested step.
  void runOurs() {
    const std::vector<double> tolerances =
        quick_ ? std::vector<double>{1e-5, 1e-8} : std::vector<double>{1e-3, 1e-5, 1e-7, 1e-9};
    for (double rtol : tolerances) {
      ds::IntegratorOptions o = ref_opt_;
      o.relative_tolerance = rtol;
      o.absolute_tolerance = rtol * abs_per_rel_;
      ours(ds::IntegratorMethod::kDopri5, o, "rtol=" + fmt(rtol));
    }
    for (double factor : quick_ ? std::vector<double>{1.0} : std::vector<double>{1.0, 0.5, 0.25}) {
      ds::IntegratorOptions o = ref_opt_;
      o.step = scene_.suggested_step * factor;
      ours(ds::IntegratorMethod::kRk4, o, "h=" + fmt(factor) + "x suggested");
    }
    for (double factor : quick_ ? std::vector<double>{1.0} : std::vector<double>{1.0, 0.25}) {
      ds::IntegratorOptions o = ref_opt_;
      o.step = scene_.suggested_step * factor;
      ours(ds::IntegratorMethod::kTrapezoidal, o, "h=" + fmt(factor) + "x suggested");
    }
  }

  void runPeers() {
    for (double rtol : quick_ ? std::vector<double>{1e-7} : std::vector<double>{1e-5, 1e-7, 1e-9}) {
      peer("odeint_dopri5", rtol, ds::bench::odeintDopri5);
    }
    // rosenbrock4 through the slice boundaries of a motion scene takes minutes per second of
    // run_up and never reaches the others' errors: not run there.
    for (double rtol : quick_          ? std::vector<double>{1e-5}
                       : scene_.motion ? std::vector<double>{1e-3, 1e-5}
                                       : std::vector<double>{1e-3, 1e-5, 1e-7}) {
      peer("odeint_rosenbrock4", rtol, ds::bench::odeintRosenbrock4);
    }
    for (double rtol : quick_ ? std::vector<double>{1e-7} : std::vector<double>{1e-5, 1e-7, 1e-9}) {
      peer("cvode_bdf", rtol, ds::bench::cvodeBdf);
    }
  }

  std::string name_;
  bool quick_;
  std::ofstream& file_;
  ds::Scene scene_;
  std::size_t expected_ = 0;
  ds::IntegratorScale scale_;
  double abs_per_rel_ = 0.0;
  ds::IntegratorOptions ref_opt_, fallback_;
  std::vector<double> ref_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "drivetrain_bench: speed against error of every method and peer on every scene (JSON lines)"};
  std::string config = std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml";
  std::string scenes_arg, out_dir = ".";
  bool plot = false, quick = false;
  app.add_option("--config", config, "gearbox YAML with gears, bearings and dynamics");
  app.add_option("--scenes", scenes_arg, "comma-separated scene names (default: all)");
  app.add_option("--out", out_dir, "directory for bench.jsonl and the PNG plots");
  app.add_flag("--plot", plot,
               "write bench_<scene>.png with scripts/plot_bench.py (python3-matplotlib)");
  app.add_flag(
      "--quick", quick,
      "fewer settings per method; the scenes whose speed changes run 0.05 s instead of 0.5 s");
  CLI11_PARSE(app, argc, argv);

  std::vector<std::string> names = ds::sceneNames();
  if (!scenes_arg.empty()) {
    names.clear();
    std::stringstream ss(scenes_arg);
    for (std::string n; std::getline(ss, n, ',');) names.push_back(n);
  }
  const ds::RigConfig rig = ds::loadRigFile(config);
  const std::string jsonl = out_dir + "/bench.jsonl";
  std::ofstream file(jsonl);
  if (!file) {
    std::cerr << "drivetrain_bench: cannot write " << jsonl << std::endl;
    return 2;
  }
  for (const std::string& name : names) SceneBench(name, rig, quick, file).run();
  file.close();
  if (plot) {
    const std::string cmd = "/usr/bin/python3 '" + std::string(DRIVETRAIN_SOURCE_DIR) +
                            "/scripts/plot_bench.py' '" + jsonl + "' '" + out_dir + "'";
    if (std::system(cmd.c_str()) != 0) {
      std::cerr << "drivetrain_bench: plotting failed (is python3-matplotlib installed?)"
                << std::endl;
      return 3;
    }
  }
  return 0;
}

// `drivetrain_cli sweep`: stepped-sine torque sweep of the rig model (seed 000 section 4.2;
// frequency_sweep.hpp): RMS per coordinate and frequency, the top three resonance peaks refined
// below the step, the record's spectral lines and, for --direction both, the largest up/down
// difference; JSON on stdout, the RMS curves as CSV with --out.
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"
#include "subcommand.hpp"

namespace drivetrain_stiffness::cli {
namespace {

struct SweepArgs {
  std::string config, fidelity = "full", direction = "up";
  SweepSpec spec;
  std::optional<std::string> out;
};

void writeSweepCsv(const SweepOutput& sweep, const std::string& path) {
  std::ofstream csv(path);
  if (!csv) throw InvalidInput("--out = '" + path + "': cannot write");
  const bool both = !sweep.rms_down[0].empty();
  csv << "frequency_hz,rms_x_p_m,rms_x_g_m,rms_x_m"
      << (both ? ",rms_down_x_p_m,rms_down_x_g_m,rms_down_x_m" : "") << '\n';
  for (std::size_t i = 0; i < sweep.frequency.size(); ++i) {
    csv << sweep.frequency[i] << ',' << sweep.rms[0][i] << ',' << sweep.rms[1][i] << ','
        << sweep.rms[2][i];
    if (both)
      csv << ',' << sweep.rms_down[0][i] << ',' << sweep.rms_down[1][i] << ','
          << sweep.rms_down[2][i];
    csv << '\n';
  }
}

int runTorqueSweep(const SweepArgs& args) {
  const RigConfig rig = loadRigFile(args.config);
  SweepSpec spec = args.spec;
  spec.fidelity = parseFidelity("--fidelity", args.fidelity);
  spec.direction = parseSweepDirection("--direction", args.direction);
  const SweepOutput sweep = torqueSweep(rig, spec);
  static const char* kNames[3] = {"x_p", "x_g", "x"};
  nlohmann::json coords = nlohmann::json::object();
  for (int c = 0; c < 3; ++c) {
    nlohmann::json peaks = nlohmann::json::array();
    for (const SpectralPeak& p : sweep.peaks[c])
      peaks.push_back({{"frequency_hz", p.frequency}, {"rms", p.amplitude}});
    nlohmann::json spectrum = nlohmann::json::array();
    for (const SpectralPeak& p : sweep.spectrum_peaks[c])
      spectrum.push_back({{"frequency_hz", p.frequency}, {"amplitude", p.amplitude}});
    coords[kNames[c]] = {{"rms", sweep.rms[c]}, {"peaks", peaks}, {"spectrum_peaks", spectrum}};
    if (!sweep.rms_down[c].empty()) {
      coords[kNames[c]]["rms_down"] = sweep.rms_down[c];
      coords[kNames[c]]["max_up_down_difference"] =
          largestRelativeDifference(sweep.rms[c], sweep.rms_down[c]);
    }
  }
  if (args.out) writeSweepCsv(sweep, *args.out);
  const nlohmann::json out = {{"fidelity", args.fidelity},
                              {"frequency_hz", sweep.frequency},
                              {"coordinates", coords},
                              {"torque_amplitude", spec.torque_amplitude},
                              {"settle_s", spec.settle},
                              {"measure_s", spec.measure},
                              {"direction", toString(spec.direction)},
                              {"sample_interval_s", sweep.sample_interval},
                              {"spectrum_resolution_hz", sweep.spectrum_resolution},
                              {"units", "Hz, m (RMS about the mean)"}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

}  // namespace

Subcommand addSweepCommand(CLI::App& app) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "frequency sweep of a sine torque fluctuation: RMS and resonance peaks");
  cmd->add_option("--config", args->config, "gearbox YAML with gears, bearings and dynamics")
      ->required();
  cmd->add_option("--start", args->spec.start, "first frequency [Hz] (default 60)");
  cmd->add_option("--stop", args->spec.stop,
                  "last frequency [Hz] (default 3000: seed 000 section 4.2)");
  cmd->add_option("--step", args->spec.step, "frequency step [Hz] (default 60)");
  cmd->add_option("--amplitude", args->spec.torque_amplitude,
                  "torque fluctuation amplitude [N·m] (default 0.05)");
  cmd->add_option("--fidelity", args->fidelity,
                  "full (dopri5, default), linear_modal or quasi_static");
  cmd->add_option("--direction", args->direction,
                  "up (default), down, or both (up then down, for jumps)");
  cmd->add_option("--out", args->out, "write frequency and RMS per coordinate to this CSV");
  return {cmd, [args] { return runTorqueSweep(*args); }};
}

}  // namespace drivetrain_stiffness::cli

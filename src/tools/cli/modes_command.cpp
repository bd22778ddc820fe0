// `drivetrain_cli modes`: natural and damped frequencies, damping ratios and mode shapes at the
// mean, single-pair and double-pair mesh stiffness, and the Floquet margin over one mesh period,
// at a pinion torque (operating_point_modes.hpp), as JSON.
#include <iostream>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/resonance/operating_point_modes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "subcommand.hpp"

namespace drivetrain_stiffness::cli {
namespace {

struct ModesArgs {
  std::string config;
  double torque = 0.1;
  std::optional<double> preload;
};

nlohmann::json modesJson(const std::array<Mode, 3>& modes) {
  nlohmann::json list = nlohmann::json::array();
  for (const Mode& m : modes) {
    list.push_back({{"natural_frequency_hz", m.natural_frequency},
                    {"damped_frequency_hz", m.damped_frequency},
                    {"damping_ratio", m.damping_ratio},
                    {"dominant_coordinate", m.dominant},
                    {"shape", {m.shape[0], m.shape[1], m.shape[2]}}});
  }
  return list;
}

int runModes(const ModesArgs& args) {
  RigConfig rig = loadRigFile(args.config);
  if (!rig.dynamics.present)
    throw InvalidInput(args.config + ": modes needs a 'dynamics:' block (masses, inertias)");
  requireFinite("--torque", args.torque);
  if (args.preload) {
    requireNonNegative("--preload", *args.preload);
    for (auto& b : rig.bearings) b.axial_preload = *args.preload;
  }
  const OperatingPointModes r = operatingPointModes(rig, args.torque);
  const GearRotorParameters& p = r.parameters;
  nlohmann::json floquet = nullptr;
  if (r.floquet) {
    floquet = {{"max_multiplier_modulus", r.floquet->result.max_modulus},
               {"margin", r.floquet->result.margin},
               {"mesh_frequency_hz", r.floquet->mesh_frequency},
               {"stable", r.floquet->result.margin > 0.0}};
  }
  const nlohmann::json out = {{"masses",
                               {{"pinion_mass", p.pinion_mass},
                                {"gear_mass", p.gear_mass},
                                {"equivalent_mass", p.equivalentMass()},
                                {"pinion_inertia", p.pinion_inertia},
                                {"gear_inertia", p.gear_inertia}}},
                              {"stiffness",
                               {{"pinion_bearing", r.bearing_stiffness[0]},
                                {"gear_bearing", r.bearing_stiffness[1]},
                                {"mesh_mean", r.mesh_mean},
                                {"mesh_min", r.mesh_range.min},
                                {"mesh_max", r.mesh_range.max}}},
                              {"damping",
                               {{"mesh", p.mesh_damping},
                                {"pinion_bearing", p.bearing_damping[0]},
                                {"gear_bearing", p.bearing_damping[1]}}},
                              {"torque", args.torque},
                              {"modes",
                               {{"mesh_mean", modesJson(r.modes_mean)},
                                {"mesh_single_pair", modesJson(r.modes_single_pair)},
                                {"mesh_double_pair", modesJson(r.modes_double_pair)}}},
                              {"floquet", floquet},
                              {"units", "Hz, N/m, kg, kg m^2, N s/m"}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

}  // namespace

Subcommand addModesCommand(CLI::App& app) {
  auto args = std::make_shared<ModesArgs>();
  CLI::App* cmd = app.add_subcommand(
      "modes", "natural and damped frequencies, damping ratios, mode shapes, Floquet margin");
  cmd->add_option("--config", args->config, "gearbox YAML with gears, bearings and dynamics")
      ->required();
  cmd->add_option("--torque", args->torque, "pinion torque [N·m] (default 0.1)");
  cmd->add_option("--preload", args->preload,
                  "axial preload of every bearing [N], overrides the file");
  return {cmd, [args] { return runModes(*args); }};
}

}  // namespace drivetrain_stiffness::cli

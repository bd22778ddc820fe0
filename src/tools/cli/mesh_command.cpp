// `drivetrain_cli mesh`: the involute geometry and the (anti-backlash composite) mesh stiffness
// over one mesh period at a pinion torque, as JSON (json_report.hpp).
#include <iostream>
#include <optional>
#include <string>

#include "drivetrain_stiffness/config/json_report.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "subcommand.hpp"

namespace drivetrain_stiffness::cli {
namespace {

struct MeshArgs {
  std::string config;
  std::optional<std::string> model;
  int samples = 100;
  double torque = 0.0;
};

int runMesh(const MeshArgs& args) {
  RigConfig rig = loadGearFile(args.config);
  if (args.model) rig.mesh_model = parseMeshStiffnessModel("--model", *args.model);
  if (args.samples < 1 || args.samples > 100000)
    throwInvalid("--samples", args.samples, "must be in [1, 100000]");
  const AntiBacklashMesh mesh(rig.gears, rig.anti_backlash, rig.mesh_model, rig.mesh_samples);
  const double force = meshForce(rig.gears, 0, args.torque);  // pinion torque -> LOA force
  std::cout << meshJson(mesh, args.samples, force).dump(2) << std::endl;
  return 0;
}

}  // namespace

Subcommand addMeshCommand(CLI::App& app) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand(
      "mesh",
      "involute geometry and (anti-backlash composite) mesh stiffness over one mesh period");
  cmd->add_option("--config", args->config,
                  "YAML file with 'gears:' (and optionally 'anti_backlash:', 'mesh:')")
      ->required();
  cmd->add_option("--model", args->model,
                  "potential_energy (default), kuang_yang (unverified) or iso6336");
  cmd->add_option("--samples", args->samples, "phases printed over one mesh period (default 100)");
  cmd->add_option("--torque", args->torque,
                  "pinion torque [N·m] setting the flank state (default 0)");
  return {cmd, [args] { return runMesh(*args); }};
}

}  // namespace drivetrain_stiffness::cli

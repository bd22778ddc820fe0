// drivetrain_cli: the core models from the command line, JSON on stdout, errors on stderr with a
// non-zero exit code. No ROS needed.
//   drivetrain_cli bearing --config FILE [--fr N] [--fa N] [--moment N·m] [--tilt free|constrained] [--preload N]
//                          [--inner-interference m] [--outer-interference m]
//   drivetrain_cli mesh --config FILE [--model potential_energy|kuang_yang|iso6336] [--samples N] [--torque N·m]
#include <CLI/CLI.hpp>
#include <iostream>
#include <optional>

#include "drivetrain_stiffness/config/json_report.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (app.got_subcommand(cmd)) return runBearing(bearing);
    if (app.got_subcommand(mesh_cmd)) return runMesh(mesh);
  } catch (const ds::InvalidInput& e) {
    std::cerr << "drivetrain_cli: invalid input: " << e.what() << std::endl;
    return 2;
  } catch (const ds::UnreachableLoad& e) {
    std::cerr << "drivetrain_cli: no equilibrium: " << e.what() << std::endl;
    return 3;
  }
  return 1;
}

// `drivetrain_cli bearing`: one bearing support's equilibrium under a load, its tangent stiffness
// and its radial secant stiffness (bearing_support.hpp), as JSON (json_report.hpp).
#include <iostream>
#include <optional>
#include <string>

#include "drivetrain_stiffness/config/json_report.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/bearing/bearing_support.hpp"
#include "subcommand.hpp"

namespace drivetrain_stiffness::cli {
namespace {

struct BearingArgs {
  std::string config;
  double fr = 0.0, fa = 0.0, moment = 0.0;
  std::optional<double> preload, inner_interference, outer_interference;
  std::optional<std::string> tilt;
};

int runBearing(const BearingArgs& args) {
  BearingSupportConfig cfg = loadBearingFile(args.config);
  if (args.preload) cfg.axial_preload = *args.preload;
  if (args.inner_interference) cfg.interference.inner = *args.inner_interference;
  if (args.outer_interference) cfg.interference.outer = *args.outer_interference;
  if (args.tilt) cfg.tilt = parseTiltCondition("--tilt", *args.tilt);
  const BearingSupport support(cfg.spec, cfg.arrangement, cfg.axial_preload, cfg.interference,
                               cfg.tilt);
  // Radial load along +x (the file's radial_preload plus --fr), axial along +z, moment about y.
  Vector5d load;
  load << cfg.radial_preload + args.fr, 0.0, args.fa, 0.0, args.moment;
  const BearingSolution sol = support.solve(load);
  const std::optional<double> secant = radialSecantStiffness(support, load, sol);
  std::cout << bearingSolutionJson(support, sol,
                                   secant ? nlohmann::json(*secant) : nlohmann::json(nullptr))
                   .dump(2)
            << std::endl;
  return 0;
}

}  // namespace

Subcommand addBearingCommand(CLI::App& app) {
  auto args = std::make_shared<BearingArgs>();
  CLI::App* cmd = app.add_subcommand("bearing", "quasi-static bearing equilibrium and stiffness");
  cmd->add_option("--config", args->config, "YAML file with a 'bearing:' block")->required();
  cmd->add_option("--fr", args->fr, "external radial load along +x [N] (added to radial_preload)");
  cmd->add_option("--fa", args->fa,
                  "external axial load along +z [N] (added to a single bearing's preload)");
  cmd->add_option("--moment", args->moment, "tilting moment about y [N·m] (needs --tilt free)");
  cmd->add_option("--tilt", args->tilt,
                  "constrained (default: shaft held in line, moment is a reaction) or free");
  cmd->add_option("--preload", args->preload, "axial preload [N], overrides the file");
  cmd->add_option("--inner-interference", args->inner_interference,
                  "diametral inner-ring interference [m]");
  cmd->add_option("--outer-interference", args->outer_interference,
                  "diametral outer-ring interference [m]");
  return {cmd, [args] { return runBearing(*args); }};
}

}  // namespace drivetrain_stiffness::cli

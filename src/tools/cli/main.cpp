// drivetrain_cli: the core models from the command line, JSON on stdout, errors on stderr with a
// non-zero exit code (2 invalid input, 3 no bearing equilibrium, 4 unstable integration). No ROS
// needed. One file per subcommand beside this one (docs/cli.md):
//   drivetrain_cli bearing --config FILE [--fr N] [--fa N] [--moment N·m] [--tilt free|constrained]
//   [--preload N]
//                          [--inner-interference m] [--outer-interference m]
//   drivetrain_cli mesh --config FILE [--model potential_energy|kuang_yang|iso6336] [--samples N]
//   [--torque N·m] drivetrain_cli simulate --config FILE --scene NAME [--method
//   dopri5|rk4|trapezoidal|exponential|quasi_static|
//                           linear_modal|auto] [--error-bound E] [--step S] [--duration S] [--rtol
//                           R] [--out CSV]
//                           [--sweep start:stop:step]
//   drivetrain_cli modes --config FILE [--torque N·m] [--preload N]
//   drivetrain_cli sweep --config FILE [--start Hz] [--stop Hz] [--step Hz] [--amplitude N·m]
//   [--fidelity F]
//                        [--direction up|down|both] [--out CSV]
//   drivetrain_cli study NAME --config FILE --out DIR [--no-png] [--plot-script PY]
#include <iostream>
#include <vector>

#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "subcommand.hpp"

namespace ds = drivetrain_stiffness;

int main(int argc, char** argv) {
  CLI::App app{"drivetrain_stiffness command-line models (SI units, JSON output)"};
  app.require_subcommand(1);
  const std::vector<ds::cli::Subcommand> subcommands{
      ds::cli::addBearingCommand(app),  ds::cli::addMeshCommand(app),
      ds::cli::addSimulateCommand(app), ds::cli::addModesCommand(app),
      ds::cli::addSweepCommand(app),    ds::cli::addStudyCommand(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    for (const ds::cli::Subcommand& s : subcommands) {
      if (app.got_subcommand(s.app)) return s.run();
    }
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

// The subcommands of drivetrain_cli, one file each: every add...Command registers its options on
// the app (CLI11) and returns what runs it, which prints JSON on stdout (nlohmann-json) and returns
// the exit code. Errors are thrown (InvalidInput, UnreachableLoad, UnstableIntegration) and mapped
// to exit codes by main.cpp.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace drivetrain_stiffness::cli {

struct Subcommand {
  CLI::App* app = nullptr;   ///< the parsed subcommand, for got_subcommand
  std::function<int()> run;  ///< runs it with the parsed options (which it owns)
};

Subcommand addBearingCommand(CLI::App& app);
Subcommand addMeshCommand(CLI::App& app);
Subcommand addSimulateCommand(CLI::App& app);
Subcommand addModesCommand(CLI::App& app);
Subcommand addSweepCommand(CLI::App& app);
Subcommand addStudyCommand(CLI::App& app);

}  // namespace drivetrain_stiffness::cli

// drivetrain_cli's subcommands: each add...Command registers its options and returns what runs it
// (JSON on stdout, the exit code); errors are thrown and main.cpp maps them to exit codes.
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

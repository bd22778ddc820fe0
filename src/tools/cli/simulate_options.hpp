// The options of `drivetrain_cli simulate`.
#pragma once

#include <optional>
#include <string>

namespace drivetrain_stiffness::cli {

struct SimulateArgs {
  std::string config, scene, method = "dopri5";
  std::optional<double> step, duration;
  double rtol = 1e-8, error_bound = 1e-6;
  std::optional<std::string> out;
  std::optional<std::string> sweep;  ///< "start:stop:step" for the oscillator scene
};

/// The backlash oscillator's up- and down-sweep as JSON; returns the exit code.
int runOscillatorSweep(const SimulateArgs& args);

}  // namespace drivetrain_stiffness::cli

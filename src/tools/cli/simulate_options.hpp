// The options of `drivetrain_cli simulate`, shared by its two runs: a scene (simulate_command.cpp)
// and the backlash oscillator's sweep (oscillator_sweep.cpp).
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

/// `simulate --scene kahraman_singh --sweep start:stop:step`: up- and down-sweep of the
/// dimensionless backlash oscillator, JSON with both branches; returns the exit code.
int runOscillatorSweep(const SimulateArgs& args);

}  // namespace drivetrain_stiffness::cli

// `drivetrain_cli simulate --scene kahraman_singh --sweep start:stop:step`: the backlash
// oscillator swept up and down in frequency with continuation (scenes.hpp, sweepOscillator), each
// branch's peak-to-peak response and impact regime as JSON; the jump hysteresis of the softening
// backlash resonance shows between the branches (Kahraman & Singh 1990).
#include <iostream>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/core/scenes/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"
#include "simulate_options.hpp"

namespace drivetrain_stiffness::cli {

int runOscillatorSweep(const SimulateArgs& args) {
  double start = 0, stop = 0, step = 0;
  char c1 = 0, c2 = 0;
  std::istringstream in(*args.sweep);
  if (!(in >> start >> c1 >> stop >> c2 >> step) || c1 != ':' || c2 != ':' || !(step > 0) ||
      !(stop > start) || start <= 0) {
    throw InvalidInput("--sweep = '" + *args.sweep +
                       "': expected start:stop:step with 0 < start < stop, step > 0");
  }
  if (args.scene != "kahraman_singh")
    throw InvalidInput("--sweep: only for --scene kahraman_singh");
  const std::vector<double> up = frequencyGrid("--sweep", start, stop, step);
  const std::vector<double> down(up.rbegin(), up.rend());
  const OscillatorSweepSpec spec;
  auto branch = [](const std::vector<SweepPoint>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const SweepPoint& p : v)
      a.push_back({{"frequency", p.frequency},
                   {"peak_to_peak", p.peak_to_peak},
                   {"min_x", p.min_x},
                   {"max_x", p.max_x},
                   {"regime", p.regime}});
    return a;
  };
  const nlohmann::json out = {{"scene", args.scene},
                              {"units", "dimensionless"},
                              {"parameters",
                               {{"zeta", spec.zeta},
                                {"mean_force", spec.mean_force},
                                {"te_force", spec.te_force},
                                {"ripple", spec.ripple},
                                {"settle_periods", spec.settle},
                                {"measure_periods", spec.measure}}},
                              {"up", branch(sweepOscillator(spec, up))},
                              {"down", branch(sweepOscillator(spec, down))}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

}  // namespace drivetrain_stiffness::cli

// Named dynamic scenes shared by the tests, drivetrain_cli simulate and the benchmark. Each is a
// reproducible hard case of the 3-DOF model (issue 4 section 3):
//   nominal              seed 000 Table 1: 1000 rpm, 0.1 N·m, TE at mesh frequency
//   torque_steps         0.1 -> 0.5 -> -0.3 (reversal inside the anti-backlash window) -> 0.1 N·m
//   low_preload          spring preload 0.01 N·m: the g2 flank separates and re-impacts under ripple
//   bearing_rattle       no torque, 10 um radial bearing clearance: the shafts rattle in the gap
//   near_rigid_bearings  bearing stiffness 1e4 x the mesh stiffness (transverse modes near 1 MHz)
//   parametric_resonance mesh frequency at twice the lowest natural frequency
//   kahraman_singh       dimensionless backlash oscillator (gear.md section 3 parameters)
//   chaotic              the same oscillator at low load, low damping, strong stiffness ripple
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/integrators.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

struct Scene {
  std::string name, description;
  std::shared_ptr<const GearRotorModel> model;
  State6 initial = State6::Zero();
  double duration = 0.0;          ///< [s] (dimensionless time for the oscillator scenes)
  double output_interval = 0.0;   ///< sampling of the time series
  double transient = 0.0;         ///< discarded before statistics
  double suggested_step = 0.0;    ///< a step that resolves the stiffest mode for explicit methods
  std::string units = "SI";       ///< "SI" or "dimensionless"
};

std::vector<std::string> sceneNames();
/// Builds a scene from the rig (gears, anti-backlash, bearings, `dynamics:` block). Throws
/// InvalidInput for an unknown name or a rig without a dynamics block.
Scene makeScene(const std::string& name, const RigConfig& rig);

/// Mean mesh stiffness over one period: k1, plus k_c for an anti-backlash gear [N/m].
double meanMeshStiffness(const AntiBacklashMesh& mesh);

/// The rotor parameters of a rig: masses and inertias from its `dynamics:` block, base radii from
/// the gears, the given bearing stiffness per shaft, and damping from the configured ratios
/// (c_s = 2 zeta sqrt(k_mean m_s) for the torsional mode, c_b = 2 zeta sqrt(k_r m) per shaft).
GearRotorParameters rigRotorParameters(const RigConfig& rig, const AntiBacklashMesh& mesh,
                                       const std::array<double, 2>& bearing_stiffness);

/// Static equilibrium of the linearised model at t (K q = f), the start state of SI scenes.
State6 staticEquilibrium(const GearRotorModel& model, double t);

/// Frequency sweep of the dimensionless backlash oscillator (Kahraman & Singh style): at each
/// frequency W the oscillator runs `settle` periods from the state the previous frequency left
/// (continuation, as a slow sweep would), then `measure` periods in which the response is
/// recorded. Up- and down-sweeps expose the jump (hysteresis) of the softening backlash resonance.
struct SweepPoint {
  double frequency = 0.0;        ///< W (dimensionless)
  double peak_to_peak = 0.0;     ///< of x over the measured periods
  double min_x = 0.0, max_x = 0.0;
  std::string regime;            ///< "no_impact", "single_sided_impact" (x < 1) or "double_sided_impact" (x < -1)
};
struct OscillatorSweepSpec {
  double zeta = 0.05, mean_force = 0.1, te_force = 0.05;
  std::array<double, 3> ripple{{0.2, 0.1, 0.05}};
  int settle = 100, measure = 50;
};
/// Runs the frequencies in the order given (ascending for an up-sweep, descending for down).
std::vector<SweepPoint> sweepOscillator(const OscillatorSweepSpec& spec, const std::vector<double>& frequencies);

}  // namespace drivetrain_stiffness

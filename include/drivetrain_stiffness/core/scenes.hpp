// Named dynamic scenes shared by the tests, drivetrain_cli simulate and the benchmark. Each is a
// reproducible hard case of the 3-DOF model (issue 4 section 3):
//   nominal              seed 000 Table 1: 1000 rpm, 0.1 N·m, TE at mesh frequency
//   torque_steps         0.1 -> 0.5 -> -0.3 (reversal inside the anti-backlash window) -> 0.1 N·m
//   low_preload          spring preload 0.01 N·m: the g2 flank separates and re-impacts under
//   ripple bearing_rattle       no torque, 10 um radial bearing clearance: the shafts rattle in the
//   gap near_rigid_bearings  bearing stiffness 1e4 x the mesh stiffness (transverse modes near 1
//   MHz) parametric_resonance mesh frequency at twice the lowest natural frequency kahraman_singh
//   dimensionless backlash oscillator (gear.md section 3 parameters) chaotic              the same
//   oscillator at low load, low damping, strong stiffness ripple
// and three scenes whose speed changes (the rig's measured motion, docs/model.md "Following the
// rig's motion"), on the sliced model (SlicedMesh) at 0.1 N·m held:
//   run_up               pinion 0 -> 6000 rpm linearly over the scene
//   speed_steps          500, 1000, 2000, 4000 rpm, a quarter of the scene each, each step a ramp
//   of 1/20 of it reverse              1000 rpm cos(2 pi t / T): through zero at T/4 to -1000 rpm
//   and back
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/integrators.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/sliced_mesh.hpp"
#include "drivetrain_stiffness/core/speed_profile.hpp"

namespace drivetrain_stiffness {

class SlicedModalPropagator;

/// The motion of a scene whose speed changes, as the node sees it: encoder readings every
/// `reading_interval` from t = 0, each giving the closed-form mesh phase of the speed profile;
/// between two readings the phase advances linearly from one reading's to the next's (the mean
/// speed over the interval). The phase is continuous and equals the closed form at every reading,
/// and inside every slice of every reading interval the sliced model is linear time-invariant, so
/// SlicedModalPropagator follows it exactly. scene.model is the same sliced model along the same
/// motion (GearRotorModel over a GearExcitation whose time events are the slice boundaries and the
/// readings), for dopri5 and the peers.
struct SceneMotion {
  SpeedProfile pinion_speed{0.0};  ///< closed-form pinion speed and angle [rad/s, rad]
  int pinion_teeth = 0;            ///< z_p: mesh phase [turns] = initial_phase + z_p angle / 2 pi
  double initial_phase = 0.0;      ///< [turns] at t = 0
  double reading_interval = 1e-3;  ///< [s], a whole number of output intervals
  std::vector<double>
      phase;  ///< [turns] at reading k (time k reading_interval), k = 0..N, unwrapped
  std::shared_ptr<const SlicedMesh> slices;
  double te_amplitude = 0.0;  ///< [m]
  double backlash = 0.0;      ///< [m]
  double drive_force = 0.0;   ///< [N] F_d = T / r_p of the torque held
  /// Mesh phase of the closed-form profile at t [turns] (no reading, no interpolation).
  double closedFormPhase(double t) const;
  /// Signed mesh frequency [Hz] between readings k and k + 1.
  double meshFrequency(std::size_t k) const { return (phase[k + 1] - phase[k]) / reading_interval; }
  std::size_t readings() const { return phase.size(); }
};

struct Scene {
  std::string name, description;
  std::shared_ptr<const GearRotorModel> model;
  State6 initial = State6::Zero();
  double duration = 0.0;         ///< [s] (dimensionless time for the oscillator scenes)
  double output_interval = 0.0;  ///< sampling of the time series
  double transient = 0.0;        ///< discarded before statistics
  double suggested_step = 0.0;   ///< a step that resolves the stiffest mode for explicit methods
  std::string units = "SI";      ///< "SI" or "dimensionless"
  /// The integrators' tolerances and limits in these units.
  IntegratorScale scale() const {
    return units == "SI" ? IntegratorScale{} : IntegratorScale::dimensionless();
  }
  /// The measured motion of the scenes whose speed changes (run_up, speed_steps, reverse); null for
  /// the scenes at a constant speed.
  std::shared_ptr<const SceneMotion> motion;
};

std::vector<std::string> sceneNames();
/// The scenes whose speed changes (a subset of sceneNames()).
std::vector<std::string> motionSceneNames();
/// Builds a scene from the rig (gears, anti-backlash, bearings, `dynamics:` block). Throws
/// InvalidInput for an unknown name or a rig without a dynamics block. `duration` > 0 [s] sets the
/// length of a motion scene (default 1 s), whose speed profile scales with it (a whole number of
/// readings; the run-up still ends at 6000 rpm); any other scene refuses it.
Scene makeScene(const std::string& name, const RigConfig& rig, double duration = 0.0);

/// The exact method on a motion scene: `exact` (built on scene.model's parameters and
/// scene.motion's slices) propagates from scene.initial along scene.motion, observed at every
/// output sample from 0 to scene.duration. A sample interval in which a contact opens is
/// integrated instead by dopri5 at `fallback` on scene.model (the same sliced model and motion),
/// counted in stats->fallbacks; stats->steps counts the slice crossings. Throws InvalidInput for a
/// scene without motion.
State6 propagateMotionScene(const Scene& scene, const SlicedModalPropagator& exact,
                            const IntegratorOptions& fallback, const Observer& observe,
                            IntegrationStats* stats = nullptr);

/// Frequency sweep of the dimensionless backlash oscillator (Kahraman & Singh style): at each
/// frequency W the oscillator runs `settle` periods from the state the previous frequency left
/// (continuation, as a slow sweep would), then `measure` periods in which the response is
/// recorded. Up- and down-sweeps expose the jump (hysteresis) of the softening backlash resonance.
struct SweepPoint {
  double frequency = 0.0;     ///< W (dimensionless)
  double peak_to_peak = 0.0;  ///< of x over the measured periods
  double min_x = 0.0, max_x = 0.0;
  std::string
      regime;  ///< "no_impact", "single_sided_impact" (x < 1) or "double_sided_impact" (x < -1)
};
struct OscillatorSweepSpec {
  double zeta = 0.05, mean_force = 0.1, te_force = 0.05;
  std::array<double, 3> ripple{{0.2, 0.1, 0.05}};
  int settle = 100, measure = 50;
};
/// Runs the frequencies in the order given (ascending for an up-sweep, descending for down).
std::vector<SweepPoint> sweepOscillator(const OscillatorSweepSpec& spec,
                                        const std::vector<double>& frequencies);

}  // namespace drivetrain_stiffness

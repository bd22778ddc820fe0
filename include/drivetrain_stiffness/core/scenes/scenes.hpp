// Named dynamic scenes of the 3-DOF model for the tests, drivetrain_cli simulate and the
// benchmark: docs/cli.md "Scenes"; the motion scenes in docs/model.md "Following the rig's motion".
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/gear/sliced_mesh.hpp"
#include "drivetrain_stiffness/core/dynamics/speed_profile.hpp"

namespace drivetrain_stiffness {

class SlicedModalPropagator;

/// The motion of a scene whose speed changes, as the node sees it: the closed-form mesh phase at
/// readings every `reading_interval`, linear between them.
struct SceneMotion {
  SpeedProfile pinion_speed{0.0};  ///< [rad/s, rad]
  int pinion_teeth = 0;            ///< z_p
  double initial_phase = 0.0;      ///< [turns] at t = 0
  double reading_interval = 1e-3;  ///< [s], a whole number of output intervals
  std::vector<double> phase;       ///< [turns] at each reading, unwrapped
  std::shared_ptr<const SlicedMesh> slices;
  double te_amplitude = 0.0;  ///< [m]
  double backlash = 0.0;      ///< [m]
  double drive_force = 0.0;   ///< [N] T / r_p
  /// The closed-form mesh phase [turns] at t [s].
  double closedFormPhase(double t) const;
  /// The signed mesh frequency [Hz] between readings k and k + 1.
  double meshFrequency(std::size_t k) const { return (phase[k + 1] - phase[k]) / reading_interval; }
  std::size_t readings() const { return phase.size(); }
};

struct Scene {
  std::string name, description;
  std::shared_ptr<const GearRotorModel> model;
  State6 initial = State6::Zero();
  double duration = 0.0;         ///< in `units`
  double output_interval = 0.0;  ///< in `units`
  double transient = 0.0;        ///< discarded before statistics
  double suggested_step = 0.0;   ///< resolves the stiffest mode for explicit methods
  std::string units = "SI";      ///< "SI" or "dimensionless"
  IntegratorScale scale() const {
    return units == "SI" ? IntegratorScale{} : IntegratorScale::dimensionless();
  }
  /// The measured motion; null at a constant speed.
  std::shared_ptr<const SceneMotion> motion;
};

std::vector<std::string> sceneNames();
/// The scenes whose speed changes.
std::vector<std::string> motionSceneNames();
/// The named scene on the rig; `duration` > 0 [s] scales a motion scene's speed profile (default
/// 1 s). Throws InvalidInput for an unknown name, a rig without a dynamics block, or a duration
/// for a scene at a constant speed.
Scene makeScene(const std::string& name, const RigConfig& rig, double duration = 0.0);

/// The exact method along a motion scene, observed at every output sample; an interval in which a
/// contact opens goes to dopri5 at `fallback` (stats->fallbacks). Throws InvalidInput for a scene
/// without motion.
State6 propagateMotionScene(const Scene& scene, const SlicedModalPropagator& exact,
                            const IntegratorOptions& fallback, const Observer& observe,
                            IntegrationStats* stats = nullptr);

/// One frequency of the dimensionless backlash oscillator's sweep (Kahraman & Singh).
struct SweepPoint {
  double frequency = 0.0;  ///< W
  double peak_to_peak = 0.0;
  double min_x = 0.0, max_x = 0.0;
  std::string regime;  ///< "no_impact", "single_sided_impact" or "double_sided_impact"
};
struct OscillatorSweepSpec {
  double zeta = 0.05, mean_force = 0.1, te_force = 0.05;
  std::array<double, 3> ripple{{0.2, 0.1, 0.05}};
  int settle = 100, measure = 50;
};
/// The frequencies in the order given, each `settle` periods from the state the previous one left,
/// then `measure` periods recorded.
std::vector<SweepPoint> sweepOscillator(const OscillatorSweepSpec& spec,
                                        const std::vector<double>& frequencies);

}  // namespace drivetrain_stiffness

// Online integration of the 3-DOF model between rig inputs (docs/model.md "Model, workspace and
// engines").
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <optional>

#include "drivetrain_stiffness/core/dynamics/dynamics_engines.hpp"

namespace drivetrain_stiffness {

struct DynamicsSample {
  double t = 0.0;  ///< [s]
  State6 state = State6::Zero();
  double dynamic_te = 0.0;  ///< delta along the LOA [m]
  double static_te = 0.0;   ///< F_m / k_s(phase) [m]
  double mesh_force = 0.0;  ///< [N]
  double phase = 0.0;       ///< [turns]
  double torque = 0.0;      ///< [N·m]
  bool drive_flank_loaded = false, back_flank_loaded = false;
};

/// What the dynamics did since construction: deterministic counts, for reports and tests.
struct DynamicsWork {
  long rebuilds = 0;            ///< builds, and parameter changes taken up while running
  long fallback_intervals = 0;  ///< intervals and stretches dopri5 took
  long mapped_stretches = 0;    ///< stretches the interval maps took
  long interval_maps_made = 0;  ///< intervals whose maps were made (0: no maps)
  bool exact = false;           ///< exact propagation now (false: dopri5, bearing clearance)
  /// The moving sliced propagator exists (the fidelity's: full, or linear_modal's mean); the
  /// counts below are its own, 0 without it.
  bool sliced = false;
  long slices_crossed = 0, decompositions = 0, general_decompositions = 0;
  long regime_changes = 0, checked_substeps = 0, kept_sets_reused = 0;
};

/// The 3-DOF dynamics on an output grid, at the nominal phase or along the measured motion.
class DynamicsEstimator {
 public:
  using Sink = std::function<void(const DynamicsSample&)>;
  /// Longest advance: output samples, slices crossed one by one.
  static constexpr double kMaxSamplesPerAdvance = 1e7;
  static constexpr double kMaxSlicesPerAdvance = 2e5;
  static constexpr int kMaxTorqueChangesPerInterval = DynamicsWorkspace::kMaxTorqueChanges;

  /// bearing_stiffness [N/m], output_rate [Hz]. Throws InvalidInput (no dynamics block,
  /// output_rate <= 0, a negative stiffness, no grid).
  DynamicsEstimator(const RigConfig& rig, const std::array<double, 2>& bearing_stiffness,
                    double output_rate);
  /// The same, rig and mesh table (of the rig) shared.
  DynamicsEstimator(std::shared_ptr<const RigConfig> rig,
                    const std::array<double, 2>& bearing_stiffness, double output_rate,
                    std::shared_ptr<const AntiBacklashMesh> mesh);

  /// Static equilibrium under `torque` [N·m] at time t [s]. Throws InvalidInput (not finite).
  void reset(double t, double torque);
  /// Integrates to t [s], each sample to sink. Throws InvalidInput (not started, t before time(),
  /// beyond kMaxSamplesPerAdvance or kMaxSlicesPerAdvance).
  void advanceTo(double t, const Sink& sink);
  void stop() { ws_.started = false; }
  /// Torque [N·m] held from `at` [s] (>= time(), no sample before), else from time(). Throws
  /// InvalidInput.
  void setTorque(double torque, std::optional<double> at = std::nullopt);
  /// Measured motion from t [s]: mesh phase [turns], mesh frequency [Hz]. Throws InvalidInput.
  void followMotion(double t, double mesh_phase, double mesh_frequency);
  bool followingMotion() const { return ws_.following; }
  /// [turns] and [Hz] at time().
  double meshPhase() const;
  double meshFrequency() const;
  /// Slices per mesh period. Throws InvalidInput (outside [4, 65536], or in use).
  void setMotionSlices(int slices);
  /// A change over 1 % as bearingGridValue(k) [N/m] from `at` [s]. Throws InvalidInput.
  void setBearingStiffness(const std::array<double, 2>& k, std::optional<double> at = std::nullopt);
  /// k [N/m] on the grid 1.01^n (k itself below 1 N/m).
  static double bearingGridValue(double k);
  /// [N/m] the model runs with.
  const std::array<double, 2>& bearingStiffness() const { return model_.bearing_stiffness; }
  /// Ratios in [0, 1]; the state is kept. Throws InvalidInput.
  void setDamping(double mesh_damping_ratio, double bearing_damping_ratio);
  const DampingRatios& damping() const { return model_.damping; }
  void setFidelity(Fidelity fidelity) { ws_.fidelity = fidelity; }
  Fidelity fidelity() const { return ws_.fidelity; }

  bool started() const { return ws_.started; }
  /// [s]
  double time() const {
    return ws_.origin + (ws_.following ? ws_.t_state : ws_.k * model_.interval);
  }
  double outputInterval() const { return model_.interval; }  ///< [s]
  /// The counts of the work done so far, and whether the propagation is exact now.
  DynamicsWork work() const;
  const RigConfig& rig() const { return *model_.rig; }
  const AntiBacklashMesh& mesh() const { return *model_.mesh; }
  /// The 3-DOF rotor model at the nominal phase (its parameters, forces and integrators).
  const GearRotorModel& rotorModel() const { return *model_.nominal; }
  /// 1 - max |Floquet multiplier| in the regime now; false in none.
  bool floquetMargin(double* margin) const;
  const State6& state() const { return ws_.y; }

 private:
  /// The engines, chosen here alone.
  EngineChoice chooseEngines();
  void build();
  void buildModel();
  void advanceNominal(double t, long k_end, const Sink& sink);
  void advanceReduced(long k_end, const Sink& sink);
  void advanceFollowing(double t_rel, const Sink& sink);
  void followFromHere(double t_rel, const Sink& sink);
  void startFollowing();
  void propagateTo(double t_rel);
  void moveTo(double t);
  void parametersChanged();
  void requireSliceBound(double t_rel) const;
  void countSlicesCrossed(double t_rel, double& crossed) const;
  DynamicsSample sample(double t_rel, const State6& y) const;
  DynamicsSample movingSample();
  DynamicsSample sampleOf(const GearRotorModel& model, double t_rel, const State6& y) const;

  DynamicsModel model_;
  DynamicsWorkspace ws_;
  PeriodicEngine periodic_;
  Dopri5Engine dopri5_;
  SlicedModalEngine sliced_;
  QuasiStaticEngine quasi_static_;
  IntervalMapsEngine maps_;
};

}  // namespace drivetrain_stiffness

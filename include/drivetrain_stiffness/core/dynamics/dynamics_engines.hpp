// DynamicsEstimator's parts (docs/model.md "Model, workspace and engines").
#pragma once

#include <array>
#include <memory>

#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_interval_maps.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"

namespace drivetrain_stiffness {

/// A sliced mesh, the model over it and its exact propagator (none with bearing clearance).
struct SlicedDynamics {
  std::shared_ptr<const SlicedMesh> slices;
  std::unique_ptr<GearRotorModel> model;
  std::unique_ptr<SlicedModalPropagator> exact;
  void build(std::shared_ptr<const SlicedMesh> mesh_slices, const GearRotorParameters& p,
             const DynamicsConfig& d);
  /// New parameters, in place (no allocation).
  void setParameters(const GearRotorParameters& p);
};

/// What describes the rig: configuration, parameters, output grid and what is built from them.
/// Only a parameter change (DynamicsEstimator's own methods) changes it. The engines take it const;
/// they set the models' torque and motion inputs, and the sliced propagators decompose their
/// slices as they are crossed (caches of the parameters alone).
struct DynamicsModel {
  std::shared_ptr<const RigConfig> rig;
  std::shared_ptr<const AntiBacklashMesh> mesh;
  DampingRatios damping;
  std::array<double, 2> bearing_stiffness{};  ///< [N/m]
  double requested_rate = 0.0;                ///< [Hz]
  IntegratorOptions fallback;                 ///< dopri5's
  double interval = 0.0;                      ///< output interval [s]
  std::unique_ptr<GearRotorModel> nominal;    ///< at the nominal phase
  std::unique_ptr<PeriodicExponentialPropagator> periodic;
  int motion_slices = 256;
  SlicedDynamics full;          ///< the fine slices
  SlicedDynamics mean;          ///< linear_modal: one slice, the period's mean
  bool periodic_stale = false;  ///< rebuild the periodic propagators at reset

  GearRotorParameters parameters() const;
  double nominalMeshFrequency() const;  ///< [Hz]
  /// F_d = T / r_b,p [N] of pinion torque [N·m].
  double driveForce(double torque) const;
  /// full, or mean for linear_modal.
  const SlicedDynamics& moving(Fidelity fidelity) const;
  /// Phase slices crossed in h [s] at mesh frequency f [Hz].
  double slicesIn(double h, double f) const;
};

/// The state and what the inputs set: time, phase, torque, counters, and the interval maps made
/// for the parameters of now.
struct DynamicsWorkspace {
  static constexpr int kMaxTorqueChanges = 16;
  /// Whether the periodic propagators' settling table holds for the interval maps.
  enum class MapsSettle { kNotAsked, kHolds, kFails };
  /// A torque input after sample k: offset [s], torque [N·m].
  struct TorqueChange {
    double offset = 0.0, torque = 0.0;
  };
  State6 y = State6::Zero();
  bool started = false;
  double origin = 0.0;  ///< time of the reset [s]
  long k = 0;           ///< output sample
  double torque = 0.0;  ///< held [N·m]
  std::array<TorqueChange, kMaxTorqueChanges> torque_change{};
  int torque_changes = 0;
  double interval_torque = 0.0;  ///< held at sample k [N·m]
  Fidelity fidelity = Fidelity::kFull;
  bool following = false;       ///< on the sliced propagation
  bool measured = false;        ///< phase from the encoders
  double t_state = 0.0;         ///< [s] since the reset
  double phase = 0.0;           ///< [turns]
  double mesh_frequency = 0.0;  ///< [Hz]
  long rebuilds = 0, fallback_intervals = 0, mapped_stretches = 0;
  std::unique_ptr<SlicedIntervalMaps> interval_maps;  ///< made on first use
  MapsSettle maps_settle = MapsSettle::kNotAsked;
  /// Drops the interval maps' verdicts after a parameter change.
  void intervalMapsStale();
};

/// What an engine did: kDone, the state carried, or why it declined, the state untouched.
enum class EngineResult {
  kDone,
  kDeclinedNoSuchOperation,     ///< the engine has no such operation
  kDeclinedNoPropagator,        ///< its propagators are not built (bearing clearance, no slices)
  kDeclinedContactsMayChange,   ///< a flank may lift and land between samples (contactsSettle)
  kDeclinedLeftLinearRegime,    ///< the exact solution leaves its linear regime
  kDeclinedNotInLoadedRegime,   ///< the state is not in the loaded regime at a stretch's end
  kDeclinedGridNotPeriodic,     ///< no whole number of output intervals per mesh period
  kDeclinedSwingGainTooLarge,   ///< the settling table does not hold for these parameters
  kDeclinedMapsNotMade,         ///< the interval's maps are not made yet (its first uses)
  kDeclinedMapsUnusable,        ///< the interval's maps have no usable slice
  kDeclinedOffGrid,             ///< the state is not on sample k
  kDeclinedPastLastBoundary,    ///< the state lies past the interval's last slice boundary
  kDeclinedWithinOneSlice,      ///< the target is in the interval's first slice: nothing to gain
  kDeclinedNothingToPropagate,  ///< the target is not after the state's time
};

/// One way of carrying the state forward, reading the model and changing the workspace: each
/// operation returns kDone or why it does not apply, the state untouched (default:
/// kDeclinedNoSuchOperation). No operation allocates in steady state (the interval maps are made
/// on first use).
class PropagationEngine {
 public:
  virtual ~PropagationEngine() = default;
  /// From sample w.k to w.k + 1, the torque changes at their stamps (the caller counts w.k).
  virtual EngineResult interval(const DynamicsModel& m, DynamicsWorkspace& w);
  /// Along the sliced propagation to t_rel [s since the reset] > w.t_state.
  virtual EngineResult propagate(const DynamicsModel& m, DynamicsWorkspace& w, double t_rel);
};

/// The periodic exponential propagators, while the contacts settle.
class PeriodicEngine final : public PropagationEngine {
 public:
  EngineResult interval(const DynamicsModel& m, DynamicsWorkspace& w) override;
};

/// dopri5 on the nominal model (interval) or the moving sliced model (propagate).
class Dopri5Engine final : public PropagationEngine {
 public:
  EngineResult interval(const DynamicsModel& m, DynamicsWorkspace& w) override;
  EngineResult propagate(const DynamicsModel& m, DynamicsWorkspace& w, double t_rel) override;
  /// From t0 to t1 [s since the reset] on the moving sliced model.
  static void stretch(const DynamicsModel& m, DynamicsWorkspace& w, double t0, double t1, State6& y,
                      double& phase);
};

/// propagateMeasured: exact between linear regimes, dopri5 stretches through the rest.
class SlicedModalEngine final : public PropagationEngine {
 public:
  EngineResult propagate(const DynamicsModel& m, DynamicsWorkspace& w, double t_rel) override;
};

/// quasi_static along the motion.
class QuasiStaticEngine final : public PropagationEngine {
 public:
  EngineResult propagate(const DynamicsModel& m, DynamicsWorkspace& w, double t_rel) override;
  /// m x'' + c x' + k x = force, exactly over h: m [kg], c [N·s/m], k [N/m], force [N], h [s].
  static void shaftStep(double m, double c, double k, double force, double h, double& x, double& v);
};

/// The interval maps at the nominal phase, where the contacts settle.
class IntervalMapsEngine final : public PropagationEngine {
 public:
  EngineResult interval(const DynamicsModel& m, DynamicsWorkspace& w) override;
  /// From sample w.k to t_rel inside the interval after it.
  EngineResult propagate(const DynamicsModel& m, DynamicsWorkspace& w, double t_rel) override;

 private:
  /// The maps' interval index into i, the maps made or taken; why not where they do not apply.
  static EngineResult mapsInterval(const DynamicsModel& m, DynamicsWorkspace& w, int& i);
};

/// `first`, and where it does not apply `fallback` (null: onto the sliced propagation).
struct EngineChoice {
  PropagationEngine* first = nullptr;
  PropagationEngine* fallback = nullptr;
};

}  // namespace drivetrain_stiffness

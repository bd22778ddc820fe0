// Online integration of the 3-DOF model between rig inputs (ROS-free; time is an argument).
//
// The state lives on a fixed output grid (the requested rate rounded so that a whole number of
// samples fits one mesh period). advanceTo(t) integrates from the last sample to the last grid
// point <= t with the measured torque held (zero-order hold from each input's own stamp: setTorque
// with `at`) and the load following it quasi-statically (drive force T / r_p), using
// the exact-exponential propagators while the contacts stay closed; at the first interval in which
// they do not, or might open and close again unseen at the samples (a torque near an anti-backlash
// knee: PeriodicExponentialPropagator::contactsSettle), the dynamics move onto the sliced
// propagation below at the nominal phase (with bearing clearance: dopri5 for that interval). Times
// are absolute seconds of the caller's clock; internally they are taken relative to the reset time
// so that 1e9-second epochs keep full phase resolution.
//
// Two ways to drive the mesh phase (docs/model.md "Following the rig's motion"):
//  - nominal: the phase counts from the last reset at the nominal speed (dynamics.speed_rpm), and
//    the periodic propagators of that one speed stream one matrix-vector product per sample;
//  - measured (followMotion, from the first call until the next reset): the phase and the speed
//    come from the rig's encoders, re-anchored at every reading, and the state is propagated
//    exactly at whatever speed (SlicedModalPropagator: the mesh sliced in phase), to any instant,
//    not only to grid points, so every input takes effect at its own stamp. A bearing-stiffness or
//    damping change also moves the dynamics onto this propagation at the nominal speed: its slices
//    are decomposed lazily as they are crossed, where the periodic propagators would have been
//    rebuilt inside the caller (8.7 ms at 1000 rpm).
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <optional>

#include "drivetrain_stiffness/core/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/sliced_interval_maps.hpp"
#include "drivetrain_stiffness/core/sliced_modal_propagator.hpp"

namespace drivetrain_stiffness {

struct DynamicsSample {
  double t = 0.0;  ///< absolute time of the sample [s]
  State6 state = State6::Zero();
  double dynamic_te = 0.0;  ///< mesh deflection delta along the LOA [m]
  double static_te = 0.0;   ///< quasi-static deflection F_m / k_s(phase) [m]
  double mesh_force = 0.0;  ///< [N]
  double phase = 0.0;       ///< mesh phase [-]
  double torque = 0.0;      ///< held pinion torque [N·m]
  bool drive_flank_loaded = false, back_flank_loaded = false;
};

class DynamicsEstimator {
 public:
  /// rig needs a dynamics block; bearing stiffness [N/m] per shaft; output rate [Hz].
  DynamicsEstimator(const RigConfig& rig, const std::array<double, 2>& bearing_stiffness,
                    double output_rate);
  /// The same with the rig shared read only (the pipeline's) and its mesh table already built (the
  /// stiffness estimator's, shared): it must be the table of rig.gears, rig.anti_backlash,
  /// rig.mesh_model and rig.mesh_samples. The damping ratios start as the rig's (setDamping).
  DynamicsEstimator(std::shared_ptr<const RigConfig> rig,
                    const std::array<double, 2>& bearing_stiffness, double output_rate,
                    std::shared_ptr<const AntiBacklashMesh> mesh);

  /// Restart at static equilibrium under `torque` at absolute time t.
  void reset(double t, double torque);
  /// Integrates to absolute time t (>= time(), else InvalidInput: reset on time jumps), calling
  /// sink for each output sample. A gap of more than kMaxSamplesPerAdvance samples is refused
  /// (InvalidInput) rather than integrated: the caller resets (a stamp of 0 followed by a
  /// wall-clock stamp would otherwise ask for 1e12 samples).
  static constexpr double kMaxSamplesPerAdvance = 1e7;
  /// Following the measured motion, the work is one step per slice crossed (plus 41 per change of
  /// the contacts located inside a step, and the dopri5 stretches through moments in no linear
  /// regime: at most kMaxNonlinearStretches per interval, then dopri5 under its step bound): an
  /// advance that would cross more than this many slices (~0.1 s of work: 0.38 s at 6000 rpm with
  /// 256 slices) is refused the same way, so that no input stalls the caller. At the nominal phase
  /// (no encoders) on the sliced propagation only the intervals crossed slice by slice count, as
  /// they come (an interval map crosses none): the samples before a refusal are given to the sink.
  static constexpr double kMaxSlicesPerAdvance = 2e5;
  void advanceTo(double t, const std::function<void(const DynamicsSample&)>& sink);
  /// Forget the state: started() is false until the next reset() (the model is kept).
  void stop() { started_ = false; }
  /// New measured torque, from `at` (absolute time >= time(), no output sample before it:
  /// advanceTo(at) first) when given, else from time(). Following the measured motion the state is
  /// at `at` already; at the nominal phase it sits on the sample before, and the next interval is
  /// integrated with the torque held before up to `at` and this one from there, exactly (full
  /// fidelity: PeriodicExponentialPropagator::torqueStepResponse; the reduced ones hold it from
  /// the sample before). At most kMaxTorqueChangesPerInterval inputs per output interval keep
  /// their own stamps; beyond that the last one's torque is replaced.
  void setTorque(double torque, std::optional<double> at = std::nullopt);
  static constexpr int kMaxTorqueChangesPerInterval = 16;
  /// The measured motion from absolute time t on: mesh phase [turns] at t and signed mesh
  /// frequency [Hz] (z_p * pinion speed / 2 pi). t >= time(); the caller has advanced to t (no
  /// output sample lies between time() and t). The state is propagated to t with the motion
  /// before, then the phase is re-anchored at the measured one.
  void followMotion(double t, double mesh_phase, double mesh_frequency);
  bool followingMotion() const { return following_; }
  /// Mesh phase [turns, not wrapped] and mesh frequency [Hz] at time(), whichever drives them.
  double meshPhase() const;
  double meshFrequency() const;
  /// Slices per mesh period of the measured-motion propagation (default 256): before its first use
  /// (InvalidInput while it runs: the encoders, or at the nominal phase after a parameter change or
  /// a torque near a knee moved the dynamics onto it, until the next reset).
  void setMotionSlices(int slices);
  /// The speed-independent propagator (null until the dynamics first move onto it: the encoders, a
  /// parameter change while running, or at the nominal phase a torque near a knee).
  const SlicedModalPropagator* slicedPropagator() const { return full_.exact.get(); }
  /// The sliced propagation the motion goes through at the current fidelity: the full model's, or
  /// under linear_modal the one-slice mean model's (null before either is made, or with bearing
  /// clearance).
  const SlicedModalPropagator* movingSlicedPropagator() const { return moving().exact.get(); }
  /// A stiffness change by more than 1 % takes effect (see the class comment); smaller ones are
  /// ignored. What takes effect is the value on a 1 % grid nearest to it (bearingGridValue: within
  /// 0.5 % of it), so that a stiffness that swings under a rippling load comes back to the same
  /// values and the sliced propagation takes their slices back instead of decomposing them again
  /// (SlicedModalPropagator::kKeptParameterSets). The stiffness given at construction is taken as
  /// it is. With `at` (absolute time >= time(), no output sample before it: advanceTo(at) first)
  /// the state is first propagated to `at` with the stiffness before, so the change takes effect at
  /// that instant rather than at the last output sample.
  void setBearingStiffness(const std::array<double, 2>& k, std::optional<double> at = std::nullopt);
  /// The grid a changed bearing stiffness [N/m] moves on: 1.01^n for the n nearest in logarithm
  /// (k itself below 1 N/m, where no rig's bearing is: 0 stays 0).
  static double bearingGridValue(double k);
  /// The bearing stiffness per shaft [N/m] the model runs with now: the last one taken up (it can
  /// differ from the estimator's by up to the 1 % above).
  const std::array<double, 2>& bearingStiffness() const { return bearing_stiffness_; }
  /// Damping ratios of the model (mesh, bearings) in place of the dynamics block's, each in [0, 1]
  /// (requireDampingRatio, InvalidInput naming the ratio otherwise); the model is rebuilt, the
  /// state kept.
  void setDamping(double mesh_damping_ratio, double bearing_damping_ratio);
  const DampingRatios& damping() const { return damping_; }
  /// full: exact-exponential / dopri5; quasi_static and linear_modal: reduced_models.hpp. The
  /// state carries over (a reduced model starts from the full state at the switch).
  void setFidelity(Fidelity fidelity);
  Fidelity fidelity() const { return fidelity_; }

  bool started() const { return started_; }
  double time() const {
    return origin_ + (following_ ? t_state_ : k_ * interval_);
  }  ///< time of the current state
  double outputInterval() const { return interval_; }
  long rebuilds() const { return rebuilds_; }
  long fallbackIntervals() const { return fallback_intervals_; }
  /// Stretches propagated by the interval maps of the nominal phase on the sliced model (after a
  /// parameter change or a torque near a knee; SlicedIntervalMaps: whole intervals, and the parts
  /// of intervals from or to an input's stamp).
  long mappedStretches() const { return mapped_stretches_; }
  /// The interval maps (null until the nominal phase first runs on the sliced model).
  const SlicedIntervalMaps* intervalMaps() const { return interval_maps_.get(); }
  bool exact() const {
    return following_ ? full_.exact != nullptr : propagator_ != nullptr;
  }  ///< exact propagation available
  const RigConfig& rig() const { return *rig_; }
  const AntiBacklashMesh& mesh() const { return *mesh_; }
  const GearRotorModel& model() const {
    return *model_;
  }  ///< nominal phase; time relative to the last reset
  /// 1 - max |Floquet multiplier| of the current model over one mesh period, from the exact
  /// propagators (a few 6x6 products); false if there is no linear regime (bearing clearance).
  /// Following the measured motion: at the measured speed held, in the contact regime the state is
  /// in (false in none, and standing still); at the nominal speed on the periodic propagators: the
  /// both-flank regime (once moved onto the sliced model, as along the measured motion).
  bool floquetMargin(double* margin) const;
  const State6& state() const { return y_; }

 private:
  void build();
  void buildModel();  ///< build() without the rebuild count and the settings named in a refusal
  DynamicsSample sample(double t_rel, const State6& y) const;
  DynamicsSample movingSample();  ///< the sample at the state (measured motion)
  /// The model over the sliced mesh the fidelity runs (linear_modal: the period's mean), its motion
  /// and torque inputs set to the state's.
  GearRotorModel& movingModelAtState();
  /// The sample of `model` (nominal or measured phase) at t_rel (relative to the last reset).
  DynamicsSample sampleOf(const GearRotorModel& model, double t_rel, const State6& y) const;
  /// Onto the measured-motion propagation at the state's time and the nominal phase there.
  void startFollowing();
  /// Measured motion: the state from t_state_ to t_rel, exact or (a contact open) dopri5.
  void propagateTo(double t_rel);
  /// quasi_static along the measured motion: the shafts exactly, the mesh in static deflection.
  void propagateQuasiStatic(double h, double drive_force);
  /// A shaft on its bearing, m x'' + c x' + k x = force held, propagated exactly over h.
  static void shaftStep(double m, double c, double k, double force, double h, double& x, double& v);
  void advanceFollowing(double t_rel, const std::function<void(const DynamicsSample&)>& sink);
  /// At the nominal phase: onto the sliced propagation from the state's sample (startFollowing),
  /// then on to t_rel there.
  void followFromHere(double t_rel, const std::function<void(const DynamicsSample&)>& sink);
  /// The nominal phase on the sliced model (after a parameter change or a torque near a knee, no
  /// encoders), full fidelity,
  /// an anti-backlash mesh whose contacts settle at the held torque (contactsSettle, as for the
  /// periodic propagators, whose table holds while the swing gain now is not above the one it was
  /// made with): the interval maps' index of the interval after sample k_; -1 where the maps do not
  /// apply. The callers check the loaded regime at each stretch's ends.
  int mapsInterval();
  /// From the state (at or after sample k_) to sample k_ + 1 by the interval maps (the part up to
  /// the next slice boundary exactly, where the state is off the grid); false, the state untouched,
  /// where they do not apply or the contacts leave the loaded regime.
  bool intervalByMaps();
  /// From the state on sample k_ to t_rel inside the interval after it: the head map of the last
  /// slice boundary before t_rel, then exactly; false, untouched, as above.
  bool headByMaps(double t_rel);
  /// Nominal phase, full fidelity: the interval from sample k_ through the torque inputs inside it;
  /// false, nothing done, where the contacts may change in it and slicedInsteadOfDopri5().
  bool advanceIntervalWithTorqueChanges();
  /// At the nominal phase an interval whose contacts may change goes onto the sliced propagation
  /// (startFollowing) rather than to dopri5 on the phase table: full fidelity, no bearing
  /// clearance.
  bool slicedInsteadOfDopri5() const;
  GearRotorParameters currentParameters() const;
  /// After a bearing-stiffness or damping change (see the class comment).
  void parametersChanged();
  /// Onto the measured-motion propagation, the state at absolute time t (>= time(), no sample
  /// before).
  void moveTo(double t);
  double nominalMeshFrequency() const;  ///< [Hz]
  /// The drive force of the held torque, F_d = T / r_b,p [N] (the live load follows the input).
  double driveForce() const;
  /// The sliced model takes other parameters: the interval maps are made again, and whether the
  /// settling table holds for them is asked again (mapsInterval).
  void intervalMapsStale();

  std::shared_ptr<const RigConfig> rig_;
  DampingRatios damping_;  ///< the rig's until setDamping
  std::array<double, 2> bearing_stiffness_;
  double requested_rate_;
  double torque_ = 0.0;  ///< the measured torque held [N·m]; also the nominal model's torque input
  /// Nominal phase: the torque inputs stamped inside the interval after sample k_ (offset from the
  /// sample [s], torque [N·m]), and the torque held at that sample.
  struct TorqueChange {
    double offset = 0.0, torque = 0.0;
  };
  std::array<TorqueChange, kMaxTorqueChangesPerInterval> torque_change_{};
  int torque_changes_ = 0;
  double interval_torque_ = 0.0;
  std::shared_ptr<const AntiBacklashMesh> mesh_;
  /// The nominal-phase model, its torque input kept equal to torque_; the propagators hold copies
  /// of their own, so a rebuild replaces each whole.
  std::unique_ptr<GearRotorModel> model_;
  std::unique_ptr<PeriodicExponentialPropagator> propagator_;
  IntegratorOptions fallback_;
  double interval_ = 0.0, origin_ = 0.0;
  long k_ = 0;
  State6 y_ = State6::Zero();
  bool started_ = false;
  // Measured motion (followMotion): over one sliced mesh, its exact propagator (none with bearing
  // clearance) and the model over it for the dopri5 stretches and the samples (its excitation
  // immutable, the motion and torque its inputs).
  struct SlicedDynamics {
    std::shared_ptr<const SlicedMesh> slices;
    std::unique_ptr<GearRotorModel> model;
    std::unique_ptr<SlicedModalPropagator> exact;
    void build(std::shared_ptr<const SlicedMesh> mesh_slices, const GearRotorParameters& p,
               const DynamicsConfig& d);
    void setParameters(
        const GearRotorParameters& p);  ///< in place: on the per-input path (allocation_tests)
  };
  /// The one the fidelity runs along the measured motion: full_, or mean_ for linear_modal.
  const SlicedDynamics& moving() const {
    return fidelity_ == Fidelity::kLinearModal ? mean_ : full_;
  }
  /// Refuses (InvalidInput, the caller resets) an advance to t_rel that would cross more than
  /// kMaxSlicesPerAdvance slices at the present mesh frequency.
  void requireSliceBound(double t_rel) const;
  /// The phase slices h [s] crosses at the present mesh frequency (the bound's measure of work).
  double slicesIn(double h) const;
  /// At the nominal phase: adds one output interval's slices to `crossed` (an advance's count of
  /// slices crossed one by one) and refuses, as requireSliceBound, once it passes the bound; t_rel
  /// is the interval's end, for the message.
  void countSlicesCrossed(double t_rel, double& crossed) const;
  int motion_slices_ = 256;
  SlicedDynamics full_;  ///< the fine slices (full fidelity, quasi_static's slice lookup)
  SlicedDynamics mean_;  ///< linear_modal: one slice holding the period's mean stiffness
  // The state's own time, phase and mesh frequency.
  bool following_ = false;
  bool measured_ =
      false;  ///< the phase comes from the encoders (followMotion since the last reset)
  std::unique_ptr<SlicedIntervalMaps> interval_maps_;
  int maps_settle_ =
      -1;  ///< the settling table holds for the parameters now: 1 yes, 0 no, -1 not yet asked
  long mapped_stretches_ = 0;
  bool periodic_stale_ =
      false;  ///< parameters changed while following: rebuild the periodic ones at reset
  double t_state_ = 0.0, phase_ = 0.0, mesh_frequency_ = 0.0;
  Fidelity fidelity_ = Fidelity::kFull;
  long rebuilds_ = 0, fallback_intervals_ = 0;
};

}  // namespace drivetrain_stiffness

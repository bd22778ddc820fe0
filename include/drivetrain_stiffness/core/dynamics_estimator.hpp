// Online integration of the 3-DOF model between rig inputs (ROS-free; time is an argument).
//
// The state lives on a fixed output grid (the requested rate rounded so that a whole number of
// samples fits one mesh period). advanceTo(t) integrates from the last sample to the last grid
// point <= t with the measured torque held (zero-order hold, applied from the next sample: latency
// <= one output interval) and the load following it quasi-statically (drive force T / r_p), using
// the exact-exponential propagators while the contacts stay closed and dopri5 for any interval in
// which they do not. The mesh phase counts from the last reset (the gear angle is not measured;
// the node assumes the nominal speed). Times are absolute seconds of the caller's clock; internally
// they are taken relative to the reset time so that 1e9-second epochs keep full phase resolution.
#pragma once

#include <array>
#include <functional>
#include <memory>

#include "drivetrain_stiffness/core/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

struct DynamicsSample {
  double t = 0.0;               ///< absolute time of the sample [s]
  State6 state = State6::Zero();
  double dynamic_te = 0.0;      ///< mesh deflection delta along the LOA [m]
  double static_te = 0.0;       ///< quasi-static deflection F_m / k_s(phase) [m]
  double mesh_force = 0.0;      ///< [N]
  double phase = 0.0;           ///< mesh phase [-]
  double torque = 0.0;          ///< held pinion torque [N·m]
  bool drive_flank_loaded = false, back_flank_loaded = false;
};

class DynamicsEstimator {
 public:
  /// rig needs a dynamics block; bearing stiffness [N/m] per shaft; output rate [Hz].
  DynamicsEstimator(const RigConfig& rig, const std::array<double, 2>& bearing_stiffness, double output_rate);
  /// The same with the rig's mesh table already built (the stiffness estimator's, shared): it must
  /// be the table of rig.gears, rig.anti_backlash, rig.mesh_model and rig.mesh_samples.
  DynamicsEstimator(const RigConfig& rig, const std::array<double, 2>& bearing_stiffness, double output_rate,
                    std::shared_ptr<const AntiBacklashMesh> mesh);

  /// Restart at static equilibrium under `torque` at absolute time t.
  void reset(double t, double torque);
  /// Integrates to absolute time t (>= time(), else InvalidInput: reset on time jumps), calling
  /// sink for each output sample. A gap of more than kMaxSamplesPerAdvance samples is refused
  /// (InvalidInput) rather than integrated: the caller resets (a stamp of 0 followed by a wall-clock
  /// stamp would otherwise ask for 1e12 samples).
  static constexpr double kMaxSamplesPerAdvance = 1e7;
  void advanceTo(double t, const std::function<void(const DynamicsSample&)>& sink);
  /// Forget the state: started() is false until the next reset() (the model is kept).
  void stop() { started_ = false; }
  /// New measured torque, applied from the next output sample.
  void setTorque(double torque);
  /// Rebuilds the model (and the propagators) when a stiffness changes by more than 1 %.
  void setBearingStiffness(const std::array<double, 2>& k);
  /// Damping ratios of the dynamics block (mesh, bearings); the model is rebuilt, the state kept.
  void setDamping(double mesh_damping_ratio, double bearing_damping_ratio);
  /// full: exact-exponential / dopri5; quasi_static and linear_modal: reduced_models.hpp. The
  /// state carries over (a reduced model starts from the full state at the switch).
  void setFidelity(Fidelity fidelity);
  Fidelity fidelity() const { return fidelity_; }

  bool started() const { return started_; }
  double time() const { return origin_ + k_ * interval_; }  ///< time of the current state
  double outputInterval() const { return interval_; }
  long rebuilds() const { return rebuilds_; }
  long fallbackIntervals() const { return fallback_intervals_; }
  bool exact() const { return propagator_ != nullptr; }  ///< exponential propagation available
  const GearRotorModel& model() const { return *model_; }  ///< time relative to the last reset
  /// 1 - max |Floquet multiplier| of the current model over one mesh period, from the exact
  /// propagators (a few 6x6 products); false if there is no linear regime (bearing clearance).
  bool floquetMargin(double* margin) const;
  const State6& state() const { return y_; }

 private:
  void build();
  void buildModel();  ///< build() without the rebuild count and the settings named in a refusal
  DynamicsSample sample(double t_rel, const State6& y) const;

  RigConfig rig_;
  std::array<double, 2> bearing_stiffness_;
  double requested_rate_;
  std::shared_ptr<double> torque_;
  std::shared_ptr<const AntiBacklashMesh> mesh_;
  std::shared_ptr<const GearRotorModel> model_;
  std::unique_ptr<PeriodicExponentialPropagator> propagator_;
  IntegratorOptions fallback_;
  double interval_ = 0.0, origin_ = 0.0;
  long k_ = 0;
  State6 y_ = State6::Zero();
  bool started_ = false;
  Fidelity fidelity_ = Fidelity::kFull;
  long rebuilds_ = 0, fallback_intervals_ = 0;
};

}  // namespace drivetrain_stiffness

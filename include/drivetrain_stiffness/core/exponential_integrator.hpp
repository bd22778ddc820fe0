// Exact-exponential propagation of the gear-rotor model in its linear regime.
//
// While every contact stays closed (both anti-backlash flanks loaded, or the drive flank of an
// ordinary gear; bearings without clearance) the model is linear with coefficients periodic in the
// mesh phase: z' = A(t) z + b u(t) with the augmented state z = [y; sin; cos; 1] (the TE at mesh
// frequency generated exactly by its own two states, the mean load by the constant state) and the
// torque fluctuation u(t) entering with a first-order hold (exact for constant torque; an output
// interval that contains a torque step is integrated by dopri5 instead, so steps stay sharp; a
// smooth fluctuation carries the hold's O(dt^2) error). One mesh period is split at the
// output samples and at the tooth-count switches; each piece is propagated by 4th-order Magnus
// steps (Gauss points, Blanes, Casas, Oteo & Ros, Phys. Rep. 470 (2009) 151, eq. 4.4) and the
// products over each output interval are stored. Streaming then costs one 9x11 matrix-vector
// product per output sample, however stiff the system is. The precomputation is done once per
// parameter set (the constructor; callers time it as setup); a sample whose contacts are no longer in the linear
// regime hands the rest of the run to dopri5 (counted as a fallback).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/core/integrators.hpp"
#include "drivetrain_stiffness/core/rig_excitation.hpp"

namespace drivetrain_stiffness {

class PeriodicExponentialPropagator {
 public:
  /// `output_interval` must divide the mesh period (within 1e-9); `step_factor` bounds each Magnus
  /// step to step_factor / omega_max. Throws InvalidInput when the model cannot be linear (bearing
  /// clearance, a model without a rig excitation). The propagator keeps its own copy of the model
  /// (with its torque input at this moment): replacing or changing the caller's model later changes
  /// nothing here.
  PeriodicExponentialPropagator(const GearRotorModel& model, double t0, double output_interval, double step_factor = 1.0);
  /// Set-up bounds (InvalidInput beyond): stored output intervals per mesh period (9x11 doubles
  /// each: 52 MB at the bound) and Magnus steps per mesh period (seconds of set-up at the bound;
  /// the seed-000 rig needs 1.7e6 at 1 rpm).
  static constexpr double kMaxIntervalsPerPeriod = 65536;
  static constexpr double kMaxSetupSteps = 2e6;

  /// The Magnus steps the constructor would take over one mesh period (period / h_max; the
  /// constructor also cuts at the table's nodes and switches, a few per cent more), without
  /// building anything: the set-up cost that `auto` weighs against the other methods.
  static double estimatedSetupSteps(const GearRotorModel& model, const RigExcitation& excitation, double t0,
                                    double step_factor = 1.0);

  int intervalsPerPeriod() const { return static_cast<int>(propagators_.size()); }
  long magnusSteps() const { return magnus_steps_; }

  using Augmented = Eigen::Matrix<double, 9, 1>;
  /// [y; sin; cos; 1] at time t (the TE generator states in phase with the excitation).
  Augmented augment(double t, const State6& y) const;
  /// One output interval: from z at sample k (time t0 + k dt) with torques u_k, u_k+1 [N·m] at its
  /// ends; returns false, leaving z untouched, if the contacts leave the linear regime.
  bool step(long k, Augmented& z, double torque_k, double torque_next) const;
  /// Homogeneous propagator over one mesh period (the monodromy matrix of the linear regime).
  Matrix6 monodromy() const;
  double t0() const { return t0_; }
  double outputInterval() const { return interval_; }

  /// Streams from (t0, y0) to t_end on the output grid; falls back to dopri5 (`fallback`) from
  /// the last linear sample if a contact opens. Returns the final state.
  State6 run(const State6& y0, double t_end, const Observer& observe, const IntegratorOptions& fallback,
             IntegrationStats* stats = nullptr) const;

 private:
  using Matrix11 = Eigen::Matrix<double, 11, 11>;
  using Propagator = Eigen::Matrix<double, 9, 11>;
  Matrix11 systemMatrix(double t) const;
  bool linearRegime(int j, const Eigen::Matrix<double, 9, 1>& z) const;

  const RigExcitation& rig() const { return *model_.rigExcitation(); }
  /// The pinion torque at t [N·m]: the model's input if it takes one (held), else the profile's.
  double torqueAt(double t) const;

  GearRotorModel model_;  ///< its own: systemMatrix(), the regime check and the dopri5 hand-over read it
  double t0_ = 0.0, interval_ = 0.0, te_amplitude_ = 0.0, te_omega_ = 0.0, te_phase_ = 0.0;
  double torque_gain_ = 0.0, mean_force_ = 0.0;
  double torque_mean_ = 0.0, preload_force_ = 0.0;  ///< [N·m], [N]: read per step
  bool held_ = false;  ///< the torque is the model's input
  std::vector<Propagator> propagators_;
  std::vector<double> k1_, kc_, backlash_offset_;  // at the sample times of one period
  long magnus_steps_ = 0;
  double divergence_limit_ = IntegratorOptions{}.divergence_limit;  ///< [m], for step()
};

}  // namespace drivetrain_stiffness

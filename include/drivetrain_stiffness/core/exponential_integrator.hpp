// Exact-exponential propagation of the gear-rotor model in its linear regime.
//
// While every contact stays closed (both anti-backlash flanks loaded, or the drive flank of an
// ordinary gear; bearings without clearance) the model is linear with coefficients periodic in the
// mesh phase: z' = A(t) z + b u(t) with the augmented state z = [y; sin; cos; 1] (the TE at mesh
// frequency generated exactly by its own two states, the mean load by the constant state) and the
// torque fluctuation u(t) entering with a first-order hold (exact for constant torque; a smooth
// fluctuation carries the hold's O(dt^2) error). A torque step inside an output interval, at any
// instant, is exact too: the system is linear, so the step adds its size times the response at the
// interval's end to a unit step at that instant (torqueStepResponse), which the constructor keeps
// the means for (the propagators from the Magnus nodes to the interval's end). One mesh period is
// split at the output samples and at the tooth-count switches; each piece is propagated by
// 4th-order Magnus steps (Gauss points, Blanes, Casas, Oteo & Ros, Phys. Rep. 470 (2009) 151,
// eq. 4.4) and the products over each output interval are stored. Streaming then costs one 9x11
// matrix-vector product per output sample, however stiff the system is. The precomputation is done
// once per parameter set (the constructor; callers time it as setup); a sample whose contacts are
// no longer in the linear regime hands the rest of the run to dopri5 (counted as a fallback).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/core/integrators.hpp"
#include "drivetrain_stiffness/core/rig_excitation.hpp"

namespace drivetrain_stiffness {

template <int P, int Q>
struct BlockTriangular;

class PeriodicExponentialPropagator {
 public:
  /// `output_interval` must divide the mesh period (within 1e-9); `step_factor` bounds each Magnus
  /// step to step_factor / omega_max. Throws InvalidInput when the model cannot be linear (bearing
  /// clearance, a model without a rig excitation). The propagator keeps its own copy of the model
  /// (with its torque input at this moment): replacing or changing the caller's model later changes
  /// nothing here.
  /// `tabulate_settling`: also tabulate contactsSettle (an anti-backlash mesh; 16 6x6
  /// eigen-decompositions and a scan of 481 forces over ~150 phases, ~3 ms).
  PeriodicExponentialPropagator(const GearRotorModel& model, double t0, double output_interval,
                                double step_factor = 1.0, bool tabulate_settling = false);
  /// Set-up bounds (InvalidInput beyond): stored output intervals per mesh period (9x11 doubles
  /// each: 52 MB at the bound) and Magnus steps per mesh period (seconds of set-up at the bound;
  /// the seed-000 rig needs 1.7e6 at 1 rpm).
  static constexpr double kMaxIntervalsPerPeriod = 65536;
  static constexpr double kMaxSetupSteps = 2e6;

  /// The Magnus steps the constructor would take over one mesh period (period / h_max), without
  /// building anything: the set-up cost that `auto` weighs against the other methods. The
  /// constructor also cuts at the table's nodes, the switches and the samples, at least one step
  /// each: on the nominal bench scene (1000 rpm, 32 samples per period) 1,809 steps against about
  /// 1,730 estimated here at step 1/omega_max, 1,164 against 866 at step 2, and 540 at the least
  /// however long the step.
  static double estimatedSetupSteps(const GearRotorModel& model, const RigExcitation& excitation,
                                    double t0, double step_factor = 1.0);

  int intervalsPerPeriod() const { return static_cast<int>(propagators_.size()); }
  long magnusSteps() const { return magnus_steps_; }

  using Augmented = Eigen::Matrix<double, 9, 1>;
  /// [y; sin; cos; 1] at time t (the TE generator states in phase with the excitation).
  Augmented augment(double t, const State6& y) const;
  /// One output interval: from z at sample k (time t0 + k dt) with torques u_k, u_k+1 [N·m] at its
  /// ends, plus `added` (the torque steps inside it: their torqueStepResponse times their size) on
  /// the state; returns false, leaving z untouched, if the contacts leave the linear regime.
  bool step(long k, Augmented& z, double torque_k, double torque_next,
            const State6* added = nullptr) const;
  /// The state at the end of output interval k in the linear regime due to a unit step of the
  /// pinion torque (1 N·m) at `offset` [s] after the interval's start (0 <= offset <= interval),
  /// everything else zero: Phi(t_k+1, t_k + offset) applied to the torque state. One Magnus step
  /// from the instant to the next stored node (and at most a few more, see kMaxStoredNodes), then a
  /// stored 6x7 product: about half a microsecond (BM_TorqueStepResponse). Built only where the
  /// torque can step (the model's own input, or a step profile); InvalidInput otherwise.
  State6 torqueStepResponse(long k, double offset) const;
  /// Stored node propagators per mesh period at most (6x7 doubles each: 2.8 MB); beyond that every
  /// n-th node is kept and torqueStepResponse takes up to n - 1 more Magnus steps.
  static constexpr long kMaxStoredNodes = 8192;
  /// False where a held pinion torque [N·m] puts the anti-backlash mesh so near a knee that the
  /// ringing after a tooth switch may lift a flank and land it again between two samples, which
  /// step() cannot see (it checks the regime at the samples): somewhere in the period the static
  /// deflection's distance to a flank threshold is below kSettleMargin times the modal bound of
  /// the swing that its step at a switch starts, or a flank is lifted at some phase. The caller
  /// integrates those intervals otherwise (DynamicsEstimator: dopri5, which locates every contact
  /// change). Always true unless the constructor tabulated it.
  bool contactsSettle(double torque) const;
  /// The swing gain the settling table was made with (max over 16 phases of sum_k |c v_k| |w_k
  /// e_x|, both flanks loaded; 0 where not tabulated): contactsSettle's answer holds for any
  /// parameters whose gain is not larger, since the rule compares margins with kSettleMargin gain
  /// J.
  double settleGain() const { return settle_gain_; }
  static constexpr double kSettleMargin = 1.5;
  /// Homogeneous propagator over one mesh period (the monodromy matrix of the linear regime).
  Matrix6 monodromy() const;
  double t0() const { return t0_; }
  double outputInterval() const { return interval_; }

  /// Streams from (t0, y0) to t_end on the output grid; falls back to dopri5 (`fallback`) from
  /// the last linear sample if a contact opens. Returns the final state.
  State6 run(const State6& y0, double t_end, const Observer& observe,
             const IntegratorOptions& fallback, IntegrationStats* stats = nullptr) const;

 private:
  using Matrix11 = Eigen::Matrix<double, 11, 11>;
  using Vector11 = Eigen::Matrix<double, 11, 1>;
  using Propagator = Eigen::Matrix<double, 9, 11>;
  Matrix11 systemMatrix(double t) const;
  void buildInterval(long j, const std::vector<double>& kinks, double h_max, const Vector11& scale,
                     const Matrix11& to_balanced, std::vector<BlockTriangular<6, 5>>& step_exps);
  /// Magnus steps over [start, start + len] [s], multiplied into phi.
  void magnusPiece(double start, double len, double h_max, const Matrix11& to_balanced,
                   std::vector<BlockTriangular<6, 5>>& step_exps, BlockTriangular<6, 5>& phi);
  void storeTails(const std::vector<BlockTriangular<6, 5>>& step_exps, const Vector11& scale);
  void tabulateSettling(const RigExcitation& excitation, const std::vector<double>& kinks,
                        double period);
  /// max over 16 phases of sum_k |c v_k| |w_k e_x|.
  double swingGain(double period) const;
  /// Interval k with the profile's torque steps; `before` [N·m] held at its start.
  Eigen::Matrix<double, 9, 1> withTorqueSteps(long k, int j, Vector11& w, double before,
                                              double t_next, IntegrationStats& st) const;
  State6 handOver(double t_k, const State6& y_k, double t_end, const Observer& observe,
                  const IntegratorOptions& fallback, IntegrationStats& st,
                  IntegrationStats* stats) const;
  std::vector<double> settle_force_;  ///< mesh forces [N], ascending, for contactsSettle
  std::vector<char> settle_ok_;
  double settle_gain_ = 0.0;
  using Matrix7 = Eigen::Matrix<double, 7, 7>;
  using Vector7 = Eigen::Matrix<double, 7, 1>;  ///< the state and the torque slot
  /// A piece's system matrix on the state and torque slot (balanced), A0 + tau A1, and [A1, A0].
  struct PieceOperators {
    Matrix7 a0, a1, commutator;
  };
  /// From the full system matrix at a third and at two thirds of a piece of this length.
  PieceOperators pieceOperators(const Matrix11& at_third, const Matrix11& at_two_thirds,
                                double length) const;
  /// One 4th-order Magnus step over [tau, tau + h] of a piece (tau from its start) applied to v
  /// (physical units), on the state and torque slot alone (with u' = 0 they evolve by themselves).
  Vector7 magnusStepOnTorque(const PieceOperators& ops, double tau, double h,
                             const Vector7& v) const;
  /// Constant-length Magnus steps of one output interval between two cuts; nodes count from the
  /// interval's start (node 0) to its end.
  struct MagnusPiece {
    double start, h;  ///< [s], in the first mesh period
    int steps, first_node;
  };
  using Tail =
      Eigen::Matrix<double, 6, 7>;  ///< Phi(interval end, node): state rows, state + torque columns
  bool linearRegime(int j, const Eigen::Matrix<double, 9, 1>& z) const;

  const RigExcitation& rig() const { return *model_.rigExcitation(); }
  /// The pinion torque at t [N·m]: the model's input if it takes one (held), else the profile's.
  double torqueAt(double t) const;

  GearRotorModel
      model_;  ///< its own: systemMatrix(), the regime check and the dopri5 hand-over read it
  double t0_ = 0.0, interval_ = 0.0, te_amplitude_ = 0.0, te_omega_ = 0.0, te_phase_ = 0.0;
  double torque_gain_ = 0.0, mean_force_ = 0.0;
  double torque_mean_ = 0.0, preload_force_ = 0.0;  ///< [N·m], [N]: read per step
  bool held_ = false;                               ///< the torque is the model's input
  std::vector<Propagator> propagators_;
  std::vector<double> k1_, kc_, backlash_offset_;  // at the sample times of one period
  std::vector<MagnusPiece> pieces_;
  std::vector<PieceOperators> piece_operators_;  ///< one per piece
  std::vector<int> piece_begin_, tail_begin_,
      node_count_;           ///< per interval (piece_begin_, tail_begin_: one more)
  std::vector<Tail> tails_;  ///< per interval, at nodes stride, 2 stride, ..., and the last
  int node_stride_ = 1;
  bool torque_steps_ = false;  ///< node products and piece operators built (torqueStepResponse)
  Vector7 scale7_;             ///< the constructor's balancing of the state and the torque slot
  long magnus_steps_ = 0;
  double divergence_limit_ = IntegratorOptions{}.divergence_limit;  ///< [m], for step()
};

}  // namespace drivetrain_stiffness

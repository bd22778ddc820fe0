// Exact-exponential propagation of the gear-rotor model's linear regime, 4th-order Magnus steps
// (Blanes, Casas, Oteo & Ros, Phys. Rep. 470 (2009) 151, eq. 4.4) (docs/model.md "Integration
// methods", "Bounds, costs and tests of the propagators").
#pragma once

#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/dynamics/rig_excitation.hpp"

namespace drivetrain_stiffness {

template <int P, int Q>
struct BlockTriangular;

class PeriodicExponentialPropagator {
 public:
  /// The products over each output interval of one mesh period, from a copy of `model`. t0 [s];
  /// output_interval [s] divides the period; Magnus steps <= step_factor / omega_max. Throws
  /// InvalidInput (bearing clearance, no rig excitation, beyond the set-up bounds).
  PeriodicExponentialPropagator(const GearRotorModel& model, double t0, double output_interval,
                                double step_factor = 1.0, bool tabulate_settling = false);
  /// Set-up bounds per mesh period: stored output intervals, Magnus steps.
  static constexpr double kMaxIntervalsPerPeriod = 65536;
  static constexpr double kMaxSetupSteps = 2e6;

  /// Magnus steps per mesh period (period / h_max), built nowhere.
  static double estimatedSetupSteps(const GearRotorModel& model, const RigExcitation& excitation,
                                    double t0, double step_factor = 1.0);

  int intervalsPerPeriod() const { return static_cast<int>(propagators_.size()); }
  long magnusSteps() const { return magnus_steps_; }

  using Augmented = Eigen::Matrix<double, 9, 1>;
  /// [y; sin; cos; 1] at time t [s].
  Augmented augment(double t, const State6& y) const;
  /// Interval k, torques [N·m] at its ends, `added` on the state; false, z untouched, where the
  /// contacts leave the linear regime.
  bool step(long k, Augmented& z, double torque_k, double torque_next,
            const State6* added = nullptr) const;
  /// Interval k's end state from a 1 N·m torque step at `offset` [s]. Throws InvalidInput.
  State6 torqueStepResponse(long k, double offset) const;
  static constexpr long kMaxStoredNodes = 8192;
  /// False where torque [N·m] may lift and land a flank between samples (true untabulated).
  bool contactsSettle(double torque) const;
  /// The settling table's swing gain (0 where not tabulated).
  double settleGain() const { return settle_gain_; }
  static constexpr double kSettleMargin = 1.5;
  /// The linear regime's monodromy over one mesh period.
  Matrix6 monodromy() const;
  double t0() const { return t0_; }
  double outputInterval() const { return interval_; }

  /// From (t0, y0) to t_end [s] on the grid; dopri5 (`fallback`) once a contact opens.
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
  std::vector<double> settle_force_;
  std::vector<char> settle_ok_;
  double settle_gain_ = 0.0;
  using Matrix7 = Eigen::Matrix<double, 7, 7>;
  using Vector7 = Eigen::Matrix<double, 7, 1>;
  /// A0 + tau A1 and [A1, A0] on the state and torque slot.
  struct PieceOperators {
    Matrix7 a0, a1, commutator;
  };
  PieceOperators pieceOperators(const Matrix11& at_third, const Matrix11& at_two_thirds,
                                double length) const;
  Vector7 magnusStepOnTorque(const PieceOperators& ops, double tau, double h,
                             const Vector7& v) const;
  struct MagnusPiece {
    double start, h;  ///< [s], in the first mesh period
    int steps, first_node;
  };
  using Tail = Eigen::Matrix<double, 6, 7>;  ///< Phi(interval end, node)
  bool linearRegime(int j, const Eigen::Matrix<double, 9, 1>& z) const;

  const RigExcitation& rig() const { return *model_.rigExcitation(); }
  /// The pinion torque at t [N·m]: the model's input, else the profile's.
  double torqueAt(double t) const;

  GearRotorModel model_;  ///< its own copy
  double t0_ = 0.0, interval_ = 0.0, te_amplitude_ = 0.0, te_omega_ = 0.0, te_phase_ = 0.0;
  double torque_gain_ = 0.0, mean_force_ = 0.0;
  double torque_mean_ = 0.0, preload_force_ = 0.0;  ///< [N·m], [N]
  bool held_ = false;
  std::vector<Propagator> propagators_;
  std::vector<double> k1_, kc_, backlash_offset_;
  std::vector<MagnusPiece> pieces_;
  std::vector<PieceOperators> piece_operators_;
  std::vector<int> piece_begin_, tail_begin_, node_count_;  ///< per interval
  std::vector<Tail> tails_;  ///< per interval, every node_stride_-th node and the last
  int node_stride_ = 1;
  bool torque_steps_ = false;
  Vector7 scale7_;
  long magnus_steps_ = 0;
  double divergence_limit_ = IntegratorOptions{}.divergence_limit;  ///< [m]
};

}  // namespace drivetrain_stiffness

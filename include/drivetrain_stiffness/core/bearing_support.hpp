// A bearing support as the rig sees it: one angular-contact or deep-groove bearing with a
// force-controlled (spring) axial preload, or a duplex pair with a position-controlled preload.
//
//  - single:        the axial preload is a constant force added to the external axial load;
//                   the spring that applies it has negligible axial stiffness.
//  - back_to_back / face_to_face (DB / DF duplex pair): both rows are clamped axially; the preload
//                   force at assembly fixes an axial offset s of each row (its pure-axial
//                   equilibrium), after which an external axial load loads one row and unloads the
//                   other. Rows sit at z = -/+ width/2; the mirrored row has its contact angle
//                   reversed (pressure centres outside the rows for DB, inside for DF).
// Displacements q are those of the shaft (inner rings) relative to the housing, from the
// assembled, centred position (bearing.md pitfall 3); see types.hpp for the ordering.
// solve() finds the equilibrium by Newton's method with the analytic tangent, a regularised
// step, a bounded trust radius and an energy line search (the stored energy is convex, so this
// converges from any start), warm-started from a previous solution when one is given, and with
// load continuation as a fallback.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/ball_bearing.hpp"

namespace drivetrain_stiffness {

enum class Arrangement { kSingle, kBackToBack, kFaceToFace };
Arrangement parseArrangement(const std::string& field, const std::string& text);
const char* toString(Arrangement arrangement);

/// Boundary condition on the ring tilt. kConstrained: the shaft is held in line by the other
/// supports (tilt prescribed as 0, the moment is a reaction, as in Harris's combined-load analysis
/// and seed 000 section 2.3); kFree: the tilt is an unknown and the applied moment is balanced.
enum class TiltCondition { kConstrained, kFree };
TiltCondition parseTiltCondition(const std::string& field, const std::string& text);
const char* toString(TiltCondition tilt);

struct SolverOptions {
  int max_iterations = 60;
  double relative_tolerance = 1e-10;  ///< on the force residual, relative to the load scale
  double absolute_tolerance = 1e-9;   ///< [N] (moments divided by R_i)
};

struct BearingSolution {
  Vector5d displacement = Vector5d::Zero();  ///< q [m, m, m, rad, rad]
  Vector5d load = Vector5d::Zero();          ///< total load carried incl. a force preload and, with
                                             ///< constrained tilt, the reaction moments [N, N·m]
  Matrix5d stiffness = Matrix5d::Zero();     ///< tangent K = df/dq [N/m, N, N·m/rad]
  std::vector<std::vector<BallState>> rows;  ///< per row, per ball
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;  ///< largest force residual [N]
  int balls_in_contact = 0;
  double max_contact_pressure = 0.0;  ///< [Pa]

  double radialStiffness() const { return stiffness(kUx, kUx); }        ///< tangent dF_x/du_x [N/m]
  double axialStiffness() const { return stiffness(kUz, kUz); }         ///< tangent dF_z/du_z [N/m]
  double tiltStiffness() const { return stiffness(kThetaY, kThetaY); }  ///< dM_y/dtheta_y [N·m/rad]
};

class BearingSupport {
 public:
  /// axial_preload [N] >= 0: spring force (single) or assembly preload (pairs; must be > 0).
  BearingSupport(const BallBearingSpec& spec, Arrangement arrangement, double axial_preload,
                 const Interference& interference = {},
                 TiltCondition tilt = TiltCondition::kConstrained,
                 const SolverOptions& options = {});
  /// Becomes BearingSupport(spec, arrangement, ...) in place, reusing the bearing's per-ball
  /// storage (no allocation for the same number of balls): the stiffness estimator rebuilds a
  /// support for new preload settings on its per-input path. Throws what the constructor throws;
  /// after a throw the support is unusable until an assign succeeds (the estimator assigns only a
  /// spare).
  void assign(const BallBearingSpec& spec, Arrangement arrangement, double axial_preload,
              const Interference& interference = {},
              TiltCondition tilt = TiltCondition::kConstrained, const SolverOptions& options = {});

  const BallBearing& bearing() const { return bearing_; }
  Arrangement arrangement() const { return arrangement_; }
  TiltCondition tiltCondition() const { return tilt_; }
  double axialPreload() const { return axial_preload_; }
  double preloadOffset() const { return offset_; }  ///< axial offset s of each pair row [m]
  int rows() const { return arrangement_ == Arrangement::kSingle ? 1 : 2; }

  /// Equilibrium under an external load [F_x, F_y, F_z, M_x, M_y] on the shaft (with constrained
  /// tilt the moments must be 0: they are reactions). Throws InvalidInput for a non-finite load and
  /// UnreachableLoad when no admissible equilibrium exists (contact pressure above
  /// spec.max_contact_pressure, an angular-contact bearing loaded against its missing shoulder, or
  /// no convergence).
  BearingSolution solve(const Vector5d& external_load, const Vector5d* warm_start = nullptr) const;
  /// The same into `out`, reusing its ball-state storage: no allocation once `out` has held a
  /// solution of this support (the stiffness estimator's per-input path). On a throw `out` is
  /// left in an unspecified state. `warm_start` may point into `out`.
  void solve(const Vector5d& external_load, const Vector5d* warm_start, BearingSolution& out) const;

  /// Energy, force and tangent of the whole support at q (used by solve and by tests).
  BearingEvaluation evaluate(const Vector5d& q) const;
  /// The load that solve() balances for a given external load (adds the spring preload).
  Vector5d totalLoad(const Vector5d& external_load) const;

 private:
  /// The constructor's checks and derived geometry once bearing_ is set.
  void configure(Arrangement arrangement, double axial_preload, TiltCondition tilt,
                 const SolverOptions& options);
  Vector5d coldStart(const Vector5d& load) const;
  bool newton(const Vector5d& load, Vector5d& q, int& iterations, double& residual) const;
  void finish(BearingSolution& sol) const;

  BallBearing bearing_;
  Arrangement arrangement_ = Arrangement::kSingle;
  double axial_preload_ = 0.0;
  TiltCondition tilt_ = TiltCondition::kConstrained;
  Vector5d free_;  ///< 1 for an unknown DOF, 0 for a prescribed one
  SolverOptions options_;
  double offset_ = 0.0;
  std::array<Matrix5d, 2> to_row_;  ///< q_row = to_row_[i] q (rigid transfer and mirror)
};

/// Radial secant stiffness F_x / (u_x(F) - u_x(F0)) [N/m] of `support` between the external load F
/// (solved: `at_load`) and the same load with F_x = 0 (F0, solved here): what a static deflection
/// measurement from no radial load to F_x sees. Null when F_x = 0. By the mean value theorem it is
/// the tangent dF_x/du_x somewhere between the two (test_bearing_support.cpp).
std::optional<double> radialSecantStiffness(const BearingSupport& support,
                                            const Vector5d& external_load,
                                            const BearingSolution& at_load);

}  // namespace drivetrain_stiffness

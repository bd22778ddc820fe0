// A bearing support: one bearing with a spring axial preload, or a clamped duplex pair (DB / DF);
// preload, boundary conditions and solver in docs/bearing_model.md "1. Model".
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/bearing/ball_bearing.hpp"

namespace drivetrain_stiffness {

enum class Arrangement { kSingle, kBackToBack, kFaceToFace };
Arrangement parseArrangement(const std::string& field, const std::string& text);
const char* toString(Arrangement arrangement);

/// The ring tilt: held at 0, the moment a reaction (seed 000 section 2.3), or free.
enum class TiltCondition { kConstrained, kFree };
TiltCondition parseTiltCondition(const std::string& field, const std::string& text);
const char* toString(TiltCondition tilt);

struct SolverOptions {
  int max_iterations = 60;
  double relative_tolerance = 1e-10;  ///< of the load scale
  double absolute_tolerance = 1e-9;   ///< [N] (moments divided by R_i)
};

struct BearingSolution {
  Vector5d displacement = Vector5d::Zero();  ///< q [m, m, m, rad, rad]
  Vector5d load = Vector5d::Zero();          ///< carried, preload and reactions included [N, N·m]
  Matrix5d stiffness = Matrix5d::Zero();     ///< tangent K = df/dq
  std::vector<std::vector<BallState>> rows;  ///< per row, per ball
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;  ///< [N]
  int balls_in_contact = 0;
  double max_contact_pressure = 0.0;  ///< [Pa]

  double radialStiffness() const { return stiffness(kUx, kUx); }        ///< [N/m]
  double axialStiffness() const { return stiffness(kUz, kUz); }         ///< [N/m]
  double tiltStiffness() const { return stiffness(kThetaY, kThetaY); }  ///< [N·m/rad]
};

class BearingSupport {
 public:
  /// axial_preload [N]: >= 0 (single), > 0 (pairs). Throws InvalidInput naming the field.
  BearingSupport(const BallBearingSpec& spec, Arrangement arrangement, double axial_preload,
                 const Interference& interference = {},
                 TiltCondition tilt = TiltCondition::kConstrained,
                 const SolverOptions& options = {});
  /// The constructor in place, allocation-free for the same number of balls. Throws as it does;
  /// after a throw the support is unusable until an assign succeeds.
  void assign(const BallBearingSpec& spec, Arrangement arrangement, double axial_preload,
              const Interference& interference = {},
              TiltCondition tilt = TiltCondition::kConstrained, const SolverOptions& options = {});

  const BallBearing& bearing() const { return bearing_; }
  Arrangement arrangement() const { return arrangement_; }
  TiltCondition tiltCondition() const { return tilt_; }
  double axialPreload() const { return axial_preload_; }
  double preloadOffset() const { return offset_; }  ///< [m] s of each pair row
  int rows() const { return arrangement_ == Arrangement::kSingle ? 1 : 2; }

  /// The equilibrium under an external load [N, N·m] on the shaft (moments 0 with constrained
  /// tilt). Throws InvalidInput for a non-finite load, UnreachableLoad when no admissible
  /// equilibrium exists.
  BearingSolution solve(const Vector5d& external_load, const Vector5d* warm_start = nullptr) const;
  /// The same into `out`, reusing its storage; `warm_start` may point into it. On a throw `out` is
  /// unspecified.
  void solve(const Vector5d& external_load, const Vector5d* warm_start, BearingSolution& out) const;

  /// U, f and K of the whole support at q.
  BearingEvaluation evaluate(const Vector5d& q) const;
  /// The external load plus the spring preload.
  Vector5d totalLoad(const Vector5d& external_load) const;

 private:
  void configure(Arrangement arrangement, double axial_preload, TiltCondition tilt,
                 const SolverOptions& options);
  Vector5d coldStart(const Vector5d& load) const;
  bool newton(const Vector5d& load, Vector5d& q, int& iterations, double& residual) const;
  void finish(BearingSolution& sol) const;

  BallBearing bearing_;
  Arrangement arrangement_ = Arrangement::kSingle;
  double axial_preload_ = 0.0;
  TiltCondition tilt_ = TiltCondition::kConstrained;
  Vector5d free_;  ///< 1: an unknown DOF, 0: prescribed
  SolverOptions options_;
  double offset_ = 0.0;
  std::array<Matrix5d, 2> to_row_;  ///< q_row = to_row_[i] q
};

/// F_x / (u_x(F) - u_x(F0)) [N/m] between the external load F (solved: `at_load`) and F with F_x =
/// 0 (docs/bearing_model.md, tangent and secant); null when F_x = 0.
std::optional<double> radialSecantStiffness(const BearingSupport& support,
                                            const Vector5d& external_load,
                                            const BearingSolution& at_load);

}  // namespace drivetrain_stiffness

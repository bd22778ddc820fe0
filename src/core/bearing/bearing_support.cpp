#include "drivetrain_stiffness/core/bearing/bearing_support.hpp"

#include <Eigen/Cholesky>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/enum_names.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

namespace {
constexpr EnumName<Arrangement> kArrangements[] = {{Arrangement::kSingle, "single"},
                                                   {Arrangement::kBackToBack, "back_to_back"},
                                                   {Arrangement::kFaceToFace, "face_to_face"}};
constexpr EnumName<TiltCondition> kTiltConditions[] = {{TiltCondition::kConstrained, "constrained"},
                                                       {TiltCondition::kFree, "free"}};
}  // namespace

Arrangement parseArrangement(const std::string& field, const std::string& text) {
  return parseEnum(kArrangements, field, text);
}
const char* toString(Arrangement a) { return enumName(kArrangements, a); }
TiltCondition parseTiltCondition(const std::string& field, const std::string& text) {
  return parseEnum(kTiltConditions, field, text);
}
const char* toString(TiltCondition tilt) { return enumName(kTiltConditions, tilt); }

namespace {
// Row transfer: a row whose ball plane sits at axial position z sees the shaft translation plus
// theta x (0, 0, z): u_x += theta_y z, u_y -= theta_x z. A mirrored row (contact angle reversed)
// sees z -> -z, which flips u_z and, for the pseudo-vector theta, theta_x and theta_y.
Matrix5d rowTransform(double z, bool mirrored) {
  Matrix5d p = Matrix5d::Identity();
  p(kUx, kThetaY) = z;
  p(kUy, kThetaX) = -z;
  if (mirrored) p.bottomRows<3>() *= -1.0;
  return p;
}
}  // namespace

BearingSupport::BearingSupport(const BallBearingSpec& spec, Arrangement arrangement,
                               double axial_preload, const Interference& interference,
                               TiltCondition tilt, const SolverOptions& options)
    : bearing_(spec, interference) {
  configure(arrangement, axial_preload, tilt, options);
}

void BearingSupport::assign(const BallBearingSpec& spec, Arrangement arrangement,
                            double axial_preload, const Interference& interference,
                            TiltCondition tilt, const SolverOptions& options) {
  bearing_.assign(spec, interference);
  configure(arrangement, axial_preload, tilt, options);
}

void BearingSupport::configure(Arrangement arrangement, double axial_preload, TiltCondition tilt,
                               const SolverOptions& options) {
  arrangement_ = arrangement;
  axial_preload_ = axial_preload;
  tilt_ = tilt;
  options_ = options;
  offset_ = 0.0;
  const BallBearingSpec& spec = bearing_.spec();
  free_ << 1.0, 1.0, 1.0, 1.0, 1.0;
  if (tilt_ == TiltCondition::kConstrained) free_[kThetaX] = free_[kThetaY] = 0.0;
  requireNonNegative("axial_preload", axial_preload);
  if (options.max_iterations < 1)
    throwInvalid("max_iterations", options.max_iterations, "must be >= 1");
  to_row_[0] = to_row_[1] = Matrix5d::Identity();
  if (arrangement_ != Arrangement::kSingle) {
    if (spec.type != BearingType::kAngularContact) {
      throw InvalidInput(std::string("arrangement = '") + toString(arrangement) +
                         "': duplex pairs need type = angular_contact");
    }
    if (!(axial_preload > 0.0))
      throwInvalid("axial_preload", axial_preload, "a duplex pair needs a preload > 0");
    try {
      offset_ = bearing_.axialDisplacementForLoad(axial_preload);
    } catch (const UnreachableLoad&
                 e) {  // named as the caller gave it: the pair's preload, not "axial_load"
      throw UnreachableLoad("axial_preload = " + formatValue(axial_preload) + ": " + e.what());
    }
    const double half = spec.width / 2.0;
    // DB: the unmirrored row (pressure centre at z - (d_m/2) tan(alpha)) on the -z side, so both
    // pressure centres lie outside the rows; DF: the other way round.
    const double z0 = arrangement_ == Arrangement::kBackToBack ? -half : half;
    to_row_[0] = rowTransform(z0, false);
    to_row_[1] = rowTransform(-z0, true);
  }
}

Vector5d BearingSupport::totalLoad(const Vector5d& external_load) const {
  Vector5d load = external_load;
  if (arrangement_ == Arrangement::kSingle) load[kUz] += axial_preload_;
  return load;
}

BearingEvaluation BearingSupport::evaluate(const Vector5d& q) const {
  if (arrangement_ == Arrangement::kSingle) return bearing_.evaluate(q);
  BearingEvaluation total;
  for (int i = 0; i < 2; ++i) {
    const Matrix5d& g = to_row_[i];
    const BearingEvaluation row = bearing_.evaluate(g * q, offset_);
    total.energy += row.energy;
    total.force += g.transpose() * row.force;
    total.stiffness += g.transpose() * row.stiffness * g;
  }
  return total;
}

Vector5d BearingSupport::coldStart(const Vector5d& load) const {
  // Start from the closed-form pure-axial solution, then add a linear radial estimate about it
  // (bearing.md pitfall 5: a zero start is singular).
  const BallBearing& b = bearing_;
  const double z = b.spec().balls;
  Vector5d q = Vector5d::Zero();
  // Axial approach of every row: from the closed-form axial solution (single bearing) or the
  // assembly offset (pair), at the centred radial separation a_r = A - Pd'/2.
  double uz_row = offset_;
  if (arrangement_ == Arrangement::kSingle) {
    uz_row = b.axialDisplacementForLoad(std::abs(load[kUz]));
    q[kUz] = std::copysign(uz_row, load[kUz]);
  }
  const double ar = b.grooveCentreDistance() - b.mountedClearance() / 2.0;
  const double l = std::hypot(ar, uz_row);
  const double delta_axial = std::max(l - b.grooveCentreDistance(), 0.0);
  const double alpha = std::atan2(uz_row, ar);
  const double radial = std::hypot(load[kUx], load[kUy]);
  if (radial > 0.0) {
    const double eps = delta_axial / l;
    const double kr =
        rows() * 0.5 * z * b.loadDeflectionConstant() * std::sqrt(delta_axial) *
        (1.5 * std::cos(alpha) * std::cos(alpha) + eps * std::sin(alpha) * std::sin(alpha));
    // Stribeck's Q_max = 5 F_r / (Z cos alpha), the usual allowance for clearance (Harris &
    // Kotzalas, load-distribution chapter), gives the radial approach when there is no preload.
    // Only a starting point: the Newton solve decides the answer.
    const double qmax = 5.0 * radial / (rows() * z * std::max(std::cos(alpha), 0.2));
    const double u_stribeck = std::pow(qmax / b.loadDeflectionConstant(), 2.0 / 3.0) +
                              std::max(b.mountedClearance(), 0.0) / 2.0;
    const double u = kr > 0.0 ? std::min(radial / kr, u_stribeck) : u_stribeck;
    q[kUx] = u * load[kUx] / radial;
    q[kUy] = u * load[kUy] / radial;
  }
  return q;
}

bool BearingSupport::newton(const Vector5d& load, Vector5d& q, int& iterations,
                            double& residual) const {
  const double ri = bearing_.innerGrooveCentreRadius();
  Vector5d scale;  // moments -> equivalent forces at the groove radius, so all residuals are in N
  scale << 1.0, 1.0, 1.0, 1.0 / ri, 1.0 / ri;
  const double load_scale = std::max({1.0, load.head<3>().cwiseAbs().maxCoeff(),
                                      load.tail<2>().cwiseAbs().maxCoeff() / ri, axial_preload_});
  const double tolerance = options_.absolute_tolerance + options_.relative_tolerance * load_scale;
  // Trust radius for one step: a fraction of the groove-centre distance A, far larger than a
  // Hertz approach but small enough to stop a step through the clearance from overshooting.
  const double trust = 0.25 * bearing_.grooveCentreDistance();
  Vector5d metric;  // natural units: rotations weighted by R_i^2
  metric << 1.0, 1.0, 1.0, ri * ri, ri * ri;
  auto potential = [&](const BearingEvaluation& e, const Vector5d& x) {
    return e.energy - load.dot(x);
  };

  BearingEvaluation eval = evaluate(q);
  Vector5d grad = (eval.force - load).cwiseProduct(free_);  // prescribed DOFs carry reactions
  for (iterations = 0; iterations < options_.max_iterations; ++iterations) {
    residual = grad.cwiseProduct(scale).cwiseAbs().maxCoeff();
    if (residual <= tolerance) return true;
    // Regularised Newton direction: K + lambda M is positive definite even where K is singular
    // (balls out of contact, a direction without stiffness).
    const double k_ref = std::max(
        eval.stiffness.diagonal().cwiseQuotient(metric).maxCoeff(),
        bearing_.loadDeflectionConstant() * std::sqrt(1e-9 * bearing_.spec().ball_diameter));
    Matrix5d a = eval.stiffness;
    a.diagonal() += 1e-10 * k_ref * metric;
    for (int i = 0; i < 5; ++i) {
      if (free_[i] != 0.0) continue;
      a.row(i).setZero();
      a.col(i).setZero();
      a(i, i) = 1.0;
    }
    Vector5d step = -a.llt().solve(grad);
    if (!step.allFinite()) return false;
    const double length = std::max(step.head<3>().norm(), ri * step.tail<2>().norm());
    if (length > trust) step *= trust / length;
    // Energy line search (Armijo), also accepting a step that halves the residual, which keeps
    // the quadratic endgame when energy differences fall below round-off.
    const double pi0 = potential(eval, q);
    const double slope = grad.dot(step);
    double t = 1.0;
    BearingEvaluation trial;
    Vector5d q_trial;
    for (int ls = 0; ls < 50; ++ls, t *= 0.5) {
      q_trial = q + t * step;
      trial = evaluate(q_trial);
      const Vector5d g_trial = (trial.force - load).cwiseProduct(free_);
      if (potential(trial, q_trial) <= pi0 + 1e-4 * t * slope ||
          g_trial.cwiseProduct(scale).cwiseAbs().maxCoeff() < 0.5 * residual) {
        break;
      }
    }
    if ((q_trial - q).head<3>().norm() + ri * (q_trial - q).tail<2>().norm() < 1e-18) {
      residual = grad.cwiseProduct(scale).cwiseAbs().maxCoeff();
      return residual <= tolerance;
    }
    q = q_trial;
    eval = trial;
    grad = (eval.force - load).cwiseProduct(free_);
  }
  residual = grad.cwiseProduct(scale).cwiseAbs().maxCoeff();
  return residual <= tolerance;
}

BearingSolution BearingSupport::solve(const Vector5d& external_load,
                                      const Vector5d* warm_start) const {
  BearingSolution sol;
  solve(external_load, warm_start, sol);
  return sol;
}

void BearingSupport::solve(const Vector5d& external_load, const Vector5d* warm_start,
                           BearingSolution& sol) const {
  static const char* kNames[5] = {"force_x", "force_y", "force_z", "moment_x", "moment_y"};
  for (int i = 0; i < 5; ++i) {
    // The name is built only on failure: this runs on every stiffness update.
    if (!std::isfinite(external_load[i]))
      throwNotFinite(std::string("load.") + kNames[i], external_load[i]);
  }
  if (tilt_ == TiltCondition::kConstrained &&
      (external_load[kThetaX] != 0.0 || external_load[kThetaY] != 0.0)) {
    throwInvalid(external_load[kThetaX] != 0.0 ? "load.moment_x" : "load.moment_y",
                 external_load[external_load[kThetaX] != 0.0 ? kThetaX : kThetaY],
                 "a moment needs tilt = free (with constrained tilt the moment is a reaction)");
  }
  if (warm_start && !warm_start->allFinite())
    throw InvalidInput("warm_start: contains a non-finite value");
  const Vector5d load = totalLoad(external_load);

  Vector5d q =
      warm_start ? *warm_start : coldStart(load);  // read before `sol` (it may hold the warm start)
  sol.load = load;
  sol.stiffness.setZero();
  sol.residual = 0.0;
  int iterations = 0;
  sol.converged = newton(load, q, iterations, sol.residual);
  sol.iterations = iterations;
  if (!sol.converged) {
    // Load continuation from the cold start: quarter steps, each warm-starting the next.
    q = coldStart(0.25 * load);
    sol.converged = true;
    for (int k = 1; k <= 4 && sol.converged; ++k) {
      sol.converged = newton(0.25 * k * load, q, iterations, sol.residual);
      sol.iterations += iterations;
    }
  }
  if (!sol.converged) {
    throw UnreachableLoad("bearing equilibrium did not converge (residual " +
                          formatValue(sol.residual) + " N after " + std::to_string(sol.iterations) +
                          " iterations) for load [" + formatValue(external_load[0]) + ", " +
                          formatValue(external_load[1]) + ", " + formatValue(external_load[2]) +
                          ", " + formatValue(external_load[3]) + ", " +
                          formatValue(external_load[4]) + "]");
  }
  sol.displacement = q;
  finish(sol);
}

void BearingSupport::finish(BearingSolution& sol) const {
  const BearingEvaluation eval = evaluate(sol.displacement);
  sol.stiffness = eval.stiffness;
  for (int i = 0; i < 5; ++i) {
    if (free_[i] == 0.0) sol.load[i] = eval.force[i];  // reaction at a prescribed DOF
  }
  sol.rows.resize(static_cast<std::size_t>(rows()));  // kept storage: no allocation per solve
  sol.balls_in_contact = 0;
  sol.max_contact_pressure = 0.0;
  for (int i = 0; i < rows(); ++i) {
    const double offset = arrangement_ == Arrangement::kSingle ? 0.0 : offset_;
    bearing_.balls(to_row_[i] * sol.displacement, offset, sol.rows[static_cast<std::size_t>(i)]);
    for (const BallState& b : sol.rows[static_cast<std::size_t>(i)]) {
      if (!b.in_contact) continue;
      ++sol.balls_in_contact;
      sol.max_contact_pressure = std::max(sol.max_contact_pressure, b.max_pressure);
      if (bearing_.spec().type == BearingType::kAngularContact && b.contact_angle < 0.0 &&
          b.load > 1e-9) {
        throw UnreachableLoad(
            "load drives a ball of an angular-contact bearing against its missing shoulder "
            "(contact angle " +
            formatValue(b.contact_angle * 180.0 / kPi) + " deg at azimuth " +
            formatValue(b.azimuth * 180.0 / kPi) +
            " deg); raise the axial preload or use type deep_groove");
      }
    }
  }
  if (sol.max_contact_pressure > bearing_.spec().max_contact_pressure) {
    throw UnreachableLoad(
        "contact pressure " + formatValue(sol.max_contact_pressure) +
        " Pa exceeds max_contact_pressure = " + formatValue(bearing_.spec().max_contact_pressure) +
        " Pa (ISO 76 static limit)");
  }
}

std::optional<double> radialSecantStiffness(const BearingSupport& support,
                                            const Vector5d& external_load,
                                            const BearingSolution& at_load) {
  if (external_load[kUx] == 0.0) return std::nullopt;
  Vector5d unloaded = external_load;
  unloaded[kUx] = 0.0;
  const BearingSolution base = support.solve(unloaded);
  return external_load[kUx] / (at_load.displacement[kUx] - base.displacement[kUx]);
}

}  // namespace drivetrain_stiffness

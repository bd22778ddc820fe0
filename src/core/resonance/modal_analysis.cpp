#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
const char* kNames[3] = {"x_p", "x_g", "x"};
}  // namespace

std::array<Mode, 3> modalAnalysis(const GearRotorParameters& p, double ks) {
  p.validate();
  requireNonNegative("mesh_stiffness", ks);
  const double ms = p.equivalentMass(), cs = p.mesh_damping;
  const Eigen::Vector3d mass(p.pinion_mass, p.gear_mass, ms);
  // docs/model.md: K and C share the mesh pattern plus the bearings.
  const Eigen::Matrix3d k = meshBearingMatrix(ks, p.bearing_stiffness),
                        c = meshBearingMatrix(cs, p.bearing_damping);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d> undamped(
      k, Eigen::Matrix3d(mass.asDiagonal()));
  if (undamped.info() != Eigen::Success)
    throw InvalidInput("modal analysis: eigen-solution failed");
  // State-space eigenvalues for the damped frequencies and damping ratios.
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
  a.topRightCorner<3, 3>().setIdentity();
  a.bottomLeftCorner<3, 3>() = -(mass.cwiseInverse().asDiagonal() * k);
  a.bottomRightCorner<3, 3>() = -(mass.cwiseInverse().asDiagonal() * c);
  const Eigen::EigenSolver<Eigen::Matrix<double, 6, 6>> state(a, false);
  std::array<std::complex<double>, 6> lambdas;
  for (int i = 0; i < 6; ++i) lambdas[i] = state.eigenvalues()[i];
  std::array<Mode, 3> modes;
  for (int i = 0; i < 3; ++i) {
    Mode& m = modes[i];
    const double w = std::sqrt(std::max(undamped.eigenvalues()[i], 0.0));
    m.natural_frequency = w / kTwoPi;
    Eigen::Vector3d v = undamped.eigenvectors().col(i);
    Eigen::Index big;
    v.cwiseAbs().maxCoeff(&big);
    if (v[big] < 0) v = -v;
    m.shape = v;
    Eigen::Index dom;
    (mass.array() * v.array().square()).maxCoeff(&dom);
    m.dominant = kNames[dom];
    // The state eigenvalue with the closest modulus (|lambda| = w_n for a lightly damped mode).
    double best = INFINITY;
    for (const auto& l : lambdas) {
      if (l.imag() < 0.0) continue;
      const double d = std::abs(std::abs(l) - w);
      if (d < best) {
        best = d;
        m.damped_frequency = std::abs(l.imag()) / kTwoPi;
        m.damping_ratio = std::abs(l) > 0.0 ? -l.real() / std::abs(l) : 0.0;
      }
    }
  }
  return modes;
}

FloquetResult floquet(const GearRotorModel& model, const State6& y_ref, double t0, double period,
                      int steps) {
  requirePositive("period", period);
  if (steps < 1) throwInvalid("steps", steps, "must be >= 1");
  Matrix6 phi;
  if (model.rigExcitation()) {
    // Exact for the linear regime: the product of the interval propagators (64 per period).
    const PeriodicExponentialPropagator propagator(model, t0, period / 64.0);
    phi = propagator.monodromy();
  } else {
    // Classical RK4 on the variational equation Phi' = J(t) Phi (J exact within a contact regime).
    phi = Matrix6::Identity();
    const double h = period / steps;
    for (int i = 0; i < steps; ++i) {
      const double t = t0 + i * h;
      const Matrix6 j1 = model.jacobian(t, y_ref), j2 = model.jacobian(t + 0.5 * h, y_ref),
                    j4 = model.jacobian(t + h, y_ref);
      const Matrix6 k1 = j1 * phi;
      const Matrix6 k2 = j2 * (phi + 0.5 * h * k1);
      const Matrix6 k3 = j2 * (phi + 0.5 * h * k2);
      const Matrix6 k4 = j4 * (phi + h * k3);
      phi += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
  }
  FloquetResult r;
  r.multipliers = Eigen::EigenSolver<Matrix6>(phi, false).eigenvalues();
  r.max_modulus = r.multipliers.cwiseAbs().maxCoeff();
  r.margin = 1.0 - r.max_modulus;
  return r;
}

}  // namespace drivetrain_stiffness

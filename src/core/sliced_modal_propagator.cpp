#include "drivetrain_stiffness/core/sliced_modal_propagator.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

using Complex = std::complex<double>;

/// phi_1(z) = (e^z - 1) / z by its Taylor series, for |z| < 0.5 (16 terms: error < 0.5^16 / 17!).
Complex phi1Series(Complex z) {
  Complex sum = 1.0, term = 1.0;
  for (int k = 2; k <= 16; ++k) {
    term *= z / static_cast<double>(k);
    sum += term;
  }
  return sum;
}

/// E(lambda, mu, h) = integral_0^h e^{lambda (h - s)} e^{mu s} ds, given e^{lambda h} and e^{mu h}.
Complex forcedIntegral(Complex lambda, Complex mu, double h, Complex e_lambda, Complex e_mu) {
  const Complex z = (mu - lambda) * h;
  if (std::abs(z) < 0.5) return h * e_lambda * phi1Series(z);  // = (e^{mu h} - e^{lambda h}) / (mu - lambda)
  return (e_mu - e_lambda) / (mu - lambda);
}

}  // namespace

SlicedModalPropagator::SlicedModalPropagator(const GearRotorParameters& p, std::shared_ptr<const SlicedMesh> slices,
                                             double te_amplitude, double backlash)
    : slices_(std::move(slices)), te_amplitude_(te_amplitude), backlash_(backlash) {
  if (!slices_) throw InvalidInput("sliced propagator: no sliced mesh");
  requireNonNegative("transmission_error_amplitude", te_amplitude);
  requireNonNegative("backlash", backlash);
  cache_.resize(static_cast<std::size_t>(slices_->size()));
  setParameters(p);
}

void SlicedModalPropagator::setParameters(const GearRotorParameters& p) {
  p.validate();
  if (p.bearing_clearance[0] > 0.0 || p.bearing_clearance[1] > 0.0) {
    throw InvalidInput("exact propagation: bearing clearance makes the model nonlinear at every crossing; use dopri5");
  }
  p_ = p;
  m_s_ = p.equivalentMass();
  for (Slice& s : cache_) s.ready = false;
}

Matrix6 SlicedModalPropagator::systemMatrix(int j) const {
  // docs/model.md eqs M1-M3 in the linear regime: mesh force F = k_s delta + c_s delta' with
  // delta = x + x_p - x_g - e (both anti-backlash flanks loaded: F_p cancels; an ordinary gear on
  // its drive flank: k_s = k1, and the constant -k1 b goes to the forcing).
  const SlicedMesh& s = *slices_;
  // y' = [[0, I], [-M^-1 K, -M^-1 C]] y with M = diag(m_p, m_g, m_s) and K, C the shared
  // mesh-and-bearing assembly (meshBearingMatrix, the modal analysis' and the scenes').
  const double ks = s.antiBacklash() ? s.k1(j) + s.kChain(j) : s.k1(j);
  const Eigen::Vector3d m_inv(1.0 / p_.pinion_mass, 1.0 / p_.gear_mass, 1.0 / m_s_);
  Matrix6 a = Matrix6::Zero();
  a.topRightCorner<3, 3>().setIdentity();
  a.bottomLeftCorner<3, 3>() = -(m_inv.asDiagonal() * meshBearingMatrix(ks, p_.bearing_stiffness));
  a.bottomRightCorner<3, 3>() = -(m_inv.asDiagonal() * meshBearingMatrix(p_.mesh_damping, p_.bearing_damping));
  return a;
}

const SlicedModalPropagator::Slice& SlicedModalPropagator::slice(int j) const {
  Slice& s = cache_[static_cast<std::size_t>(j)];
  if (s.ready) return s;
  const Matrix6 a = systemMatrix(j);
  // Balance displacements against velocities (scale omega_ref = sqrt(max |A_vx|)) so that the
  // eigenvectors are well scaled; A = D A_b D^-1, V = D V_b, V^-1 = V_b^-1 D^-1.
  const double w_ref = std::sqrt(std::max(1.0, a.block<3, 3>(3, 0).cwiseAbs().maxCoeff()));
  Eigen::Matrix<double, 6, 1> d;
  d << 1.0, 1.0, 1.0, w_ref, w_ref, w_ref;
  const Matrix6 a_b = d.cwiseInverse().asDiagonal() * a * d.asDiagonal();
  const Eigen::EigenSolver<Matrix6> eig(a_b, true);
  ++decompositions_;
  s.usable = eig.info() == Eigen::Success;
  if (s.usable) {
    const CMatrix v_b = eig.eigenvectors();
    const Eigen::PartialPivLU<CMatrix> lu(v_b);
    const CMatrix v_b_inv = lu.inverse();
    // A defective (critically damped) or nearly defective pair has no usable eigenbasis: dopri5 takes it.
    const double condition = v_b.cwiseAbs().rowwise().sum().maxCoeff() * v_b_inv.cwiseAbs().rowwise().sum().maxCoeff();
    s.usable = std::isfinite(condition) && condition < 1e8;
    s.lambda = eig.eigenvalues();
    s.v = d.cast<Complex>().asDiagonal() * v_b;
    s.v_inv = v_b_inv * d.cwiseInverse().cast<Complex>().asDiagonal();
    Eigen::Matrix<double, 6, 1> e_f, e_v;
    e_f << 0.0, 0.0, 0.0, -1.0 / p_.pinion_mass, 1.0 / p_.gear_mass, -1.0 / m_s_;
    e_v << 0.0, 0.0, 0.0, 0.0, 0.0, 1.0 / m_s_;
    s.force_dir = s.v_inv * e_f.cast<Complex>();
    s.drive_dir = s.v_inv * e_v.cast<Complex>();
    // Conjugate pairs: Eigen's EigenSolver returns a complex pair's eigenvectors as conjugates, so
    // for a real state and real forcing the pair's modal coordinates are conjugates too.
    s.weight.fill(1.0);
    for (int k = 0; k < 6; ++k) {
      if (s.weight[k] == 0.0 || s.lambda[k].imag() == 0.0) continue;
      for (int j = k + 1; j < 6; ++j) {
        const bool pair = s.weight[j] != 0.0 && std::abs(s.lambda[j] - std::conj(s.lambda[k])) <= 1e-12 * std::abs(s.lambda[k]) &&
                          (s.v.col(j) - s.v.col(k).conjugate()).cwiseAbs().maxCoeff() <= 1e-12 * s.v.col(k).cwiseAbs().maxCoeff();
        if (pair) {
          s.weight[k] = 2.0;
          s.weight[j] = 0.0;
          break;
        }
      }
      if (s.weight[k] != 2.0) s.usable = false;  // a complex eigenvalue without its conjugate: not a real system's
    }
  }
  s.ready = true;
  return s;
}

void SlicedModalPropagator::step(const Slice& s, int j, State6& y, double theta0, double w, double h,
                                 double drive_force) const {
  const SlicedMesh& m = *slices_;
  const double ks = m.antiBacklash() ? m.k1(j) + m.kChain(j) : m.k1(j);
  // Forcing in modal coordinates: U sin(theta) + W w cos(theta) + G, written as
  // P e^{i w s} + Q e^{-i w s} + G with sin x = (e^{ix} - e^{-ix}) / 2i, cos x = (e^{ix} + e^{-ix}) / 2.
  const double u = -ks * te_amplitude_, wc = -p_.mesh_damping * te_amplitude_ * w;
  const double constant = m.antiBacklash() ? 0.0 : -m.k1(j) * backlash_;
  const Complex e0(std::cos(theta0), std::sin(theta0));
  const Complex p_coef = e0 * Complex(0.5 * wc, -0.5 * u), q_coef = std::conj(e0) * Complex(0.5 * wc, 0.5 * u);
  const Complex mu(0.0, w);
  const Complex e_mu = std::exp(mu * h), e_mu_conj = std::conj(e_mu);
  State6 next = State6::Zero();
  for (int k = 0; k < 6; ++k) {
    if (s.weight[k] == 0.0) continue;  // the conjugate of a mode already counted twice
    const Complex lambda = s.lambda[k];
    Complex eta0 = 0.0;  // row k of V^-1 y (complex times real)
    for (int i = 0; i < 6; ++i) eta0 += s.v_inv(k, i) * y[i];
    const Complex e_l = std::exp(lambda * h);
    const Complex g = s.force_dir[k] * constant + s.drive_dir[k] * drive_force;
    const Complex eta = e_l * eta0 +
                        s.force_dir[k] * (p_coef * forcedIntegral(lambda, mu, h, e_l, e_mu) +
                                          q_coef * forcedIntegral(lambda, -mu, h, e_l, e_mu_conj)) +
                        g * forcedIntegral(lambda, 0.0, h, e_l, 1.0);
    next += s.weight[k] * (s.v.col(k) * eta).real();
  }
  y = next;
}

bool SlicedModalPropagator::linearRegime(int j, const State6& y, double theta, double w) const {
  // The same conditions as GearRotorModel::forces in its linear regime: every spring closed and
  // no damper force clipped (Modelica ElastoBacklash's rule: the damper never pulls, |F_d| <= F_s).
  const SlicedMesh& m = *slices_;
  const double delta = y[2] + y[0] - y[1] - te_amplitude_ * std::sin(theta);
  const double rate = y[5] + y[3] - y[4] - te_amplitude_ * w * std::cos(theta);
  const double k1 = m.k1(j), kc = m.kChain(j);
  if (m.antiBacklash()) {
    const double fp = m.mesh().preloadForce();
    const double c1 = p_.mesh_damping * k1 / (k1 + kc), c2 = p_.mesh_damping - c1;
    const double s1 = fp + k1 * delta, s2 = fp - kc * delta;
    const double t1 = s1 + c1 * rate, t2 = s2 - c2 * rate;
    return s1 > 0.0 && s2 > 0.0 && t1 >= 0.0 && t1 <= 2.0 * s1 && t2 >= 0.0 && t2 <= 2.0 * s2;
  }
  const double g = delta - backlash_;
  const double total = k1 * g + p_.mesh_damping * rate;
  return g > 0.0 && total >= 0.0 && total <= 2.0 * k1 * g;
}

bool SlicedModalPropagator::propagate(State6& y, double& phase, double f, double duration, double drive_force) const {
  if (!(duration >= 0.0) || !std::isfinite(f) || !std::isfinite(phase) || !std::isfinite(drive_force)) return false;
  const SlicedMesh& m = *slices_;
  const double w = kTwoPi * f;
  State6 z = y;
  double whole = std::floor(phase), frac = phase - whole, remaining = duration;
  while (remaining > 0.0) {
    if (f < 0.0 && frac == 0.0) {  // backwards from a period boundary: the top of the period below
      whole -= 1.0;
      frac = 1.0;
    }
    const int j = m.sliceAt(frac == 1.0 ? std::nextafter(1.0, 0.0) : frac, f < 0.0);
    const Slice& s = slice(j);
    if (!s.usable) return false;
    double h = remaining, next = frac + f * remaining;
    bool crossing = false;
    if (f != 0.0) {
      const double boundary = f > 0.0 ? m.end(j) : m.start(j);
      const double to_boundary = (boundary - frac) / f;
      if (to_boundary <= remaining) {
        h = to_boundary;
        next = boundary;  // exactly on it: the next piece starts in the next slice, no drift
        crossing = true;
      }
    }
    step(s, j, z, kTwoPi * frac, w, h, drive_force);
    remaining = crossing ? remaining - h : 0.0;
    frac = next;
    if (frac >= 1.0) {
      whole += 1.0;
      frac -= 1.0;
    }
    if (!z.allFinite() || !linearRegime(j, z, kTwoPi * frac, w)) return false;
    if (crossing) {
      ++crossed_;
      // Right limit: the slice entered must also hold the contacts closed.
      const int entered = m.sliceAt(frac, f < 0.0);
      if (!linearRegime(entered, z, kTwoPi * frac, w)) return false;
    }
  }
  y = z;
  phase = whole + frac;
  return true;
}

Matrix6 SlicedModalPropagator::monodromy(double f) const {
  requireFinite("mesh frequency", f);
  if (f == 0.0) throw InvalidInput("monodromy: the mesh must turn (mesh frequency 0)");
  Matrix6 phi = Matrix6::Identity();
  const int n = slices_->size();
  for (int i = 0; i < n; ++i) {
    const int j = f > 0.0 ? i : n - 1 - i;
    const Slice& s = slice(j);
    const double tau = (slices_->end(j) - slices_->start(j)) / std::abs(f);
    CVector e;
    for (int k = 0; k < 6; ++k) e[k] = std::exp(s.lambda[k] * tau);
    phi = (s.v * e.asDiagonal() * s.v_inv).real() * phi;
  }
  return phi;
}

}  // namespace drivetrain_stiffness

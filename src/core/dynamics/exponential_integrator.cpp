#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <Eigen/Eigenvalues>
#include <complex>
#include <stdexcept>
#include <unsupported/Eigen/MatrixFunctions>

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/dynamics/block_triangular_exponential.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

bool stepInside(const TorqueProfile& torque, double a, double b) {
  for (const auto& s : torque.steps) {
    if (s.first > a && s.first <= b) return true;
  }
  return false;
}
// The stiffest natural scale [rad/s], which bounds the Magnus step (convergence needs the integral
// of ||A|| < pi): the fastest of the shafts on their bearings with the stiffest mesh, the
// torsional mode and the TE forcing.
double fastestRate(const GearRotorModel& model, const RigExcitation& excitation, double t0) {
  const GearRotorParameters& p = model.parameters();
  const double period = 1.0 / excitation.meshFrequency(),
               te_omega = kTwoPi * excitation.meshFrequency();
  double k_max = 0.0;
  for (int i = 0; i < 64; ++i) {
    MeshInstant mi;
    excitation.at(t0 + period * (i + 0.5) / 64, mi);
    k_max = std::max(k_max, mi.k_drive + mi.k_back);
  }
  return std::sqrt(std::max({(k_max + p.bearing_stiffness[0]) / p.pinion_mass,
                             (k_max + p.bearing_stiffness[1]) / p.gear_mass,
                             2.0 * k_max / model.equivalentMass(), te_omega * te_omega}));
}
// State indices of the augmented system.
enum : int { kXp = 0, kXg, kX, kVp, kVg, kV, kSin, kCos, kOne, kU, kUdot };

// Output intervals per mesh period [s] at output_interval [s]: InvalidInput where they are more
// than `most` or do not divide the period.
long gridIntervals(double period, double output_interval, double most) {
  const double n_real = period / output_interval;
  // Checked before lround: a slow mesh on a fine grid asks for more intervals than a long holds.
  if (!(n_real <= most)) {
    throwInvalid("output_interval", output_interval,
                 "gives " + formatValue(n_real) + " samples per mesh period of " +
                     formatValue(period) + " s: more than " + formatValue(most) +
                     " stored propagators");
  }
  const long n = std::lround(n_real);
  if (n < 1 || std::abs(n_real - n) > 1e-9 * n_real) {
    throwInvalid("output_interval", output_interval,
                 "must divide the mesh period " + formatValue(period) + " s");
  }
  return n;
}

// The times in (t0, t0 + period) where A(t) has a kink, sorted: every node of the phase table and
// every tooth-count switch, so that A(t) is linear in t inside each piece between them and the
// Gauss-point Magnus step keeps its order.
std::vector<double> kinkTimes(const RigExcitation& excitation, double t0, double period) {
  std::vector<double> kinks;
  const std::vector<double> nodes = excitation.mesh().tableNodePhases();
  const double f = excitation.meshFrequency(), phase0 = excitation.spec().initial_phase;
  const double first_turn = std::floor(phase0 + f * t0);
  for (int cycle = 0; cycle <= 1; ++cycle) {
    for (double node : nodes) {
      const double t = (first_turn + cycle + node - phase0) / f;
      if (t > t0 && t < t0 + period) kinks.push_back(t);
    }
  }
  for (double t = excitation.nextSwitch(t0); t < t0 + period; t = excitation.nextSwitch(t))
    kinks.push_back(t);
  std::sort(kinks.begin(), kinks.end());
  return kinks;
}
}  // namespace

double PeriodicExponentialPropagator::torqueAt(double t) const {
  return held_ ? model_.torqueInput() : rig().spec().torque.at(t);
}

PeriodicExponentialPropagator::PeriodicExponentialPropagator(const GearRotorModel& model, double t0,
                                                             double output_interval,
                                                             double step_factor,
                                                             bool tabulate_settling)
    : model_(model), t0_(t0), interval_(output_interval) {
  if (!model_.rigExcitation())
    throw InvalidInput(
        "method exponential: needs a rig excitation (mesh stiffness periodic in the mesh phase)");
  const RigExcitation& excitation = rig();
  const GearRotorParameters& p = model.parameters();
  if (p.bearing_clearance[0] > 0.0 || p.bearing_clearance[1] > 0.0) {
    throw InvalidInput(
        "method exponential: bearing clearance makes the model nonlinear at every crossing; use "
        "dopri5");
  }
  requireFinite("t0", t0);
  requirePositive("output_interval", output_interval);
  requirePositive("magnus_step_factor", step_factor);
  const RigExcitationSpec& spec = excitation.spec();
  const double period = 1.0 / excitation.meshFrequency();
  const long n = gridIntervals(period, output_interval, kMaxIntervalsPerPeriod);
  te_amplitude_ = spec.te_amplitude;
  te_omega_ = kTwoPi * excitation.meshFrequency();
  te_phase_ = kTwoPi * spec.initial_phase;
  torque_gain_ = excitation.torqueGain();
  torque_mean_ = spec.torque.mean;
  held_ = excitation.takesTorqueInput();
  preload_force_ = excitation.mesh().preloadForce();
  MeshInstant m;
  model_.meshAt(t0, m);
  mean_force_ = m.drive_force - torque_gain_ * (torqueAt(t0) - spec.torque.mean);

  const double w_max = fastestRate(model, excitation, t0);
  const double h_max = step_factor / w_max;
  // The set-up costs one Magnus step (an 11x11 exponential, ~5 us) per h_max over a mesh period:
  // a slow mesh makes that hours (0.001 rpm on the seed-000 rig: 2e9 steps). Refused up front.
  if (!(period / h_max <= kMaxSetupSteps)) {
    throwInvalid("mesh period", period,
                 "needs " + formatValue(period / h_max) + " Magnus steps to set up (more than " +
                     formatValue(kMaxSetupSteps) + "): the mesh is too slow for exact propagation");
  }

  const std::vector<double> kinks = kinkTimes(excitation, t0, period);

  // Balance the state before exponentiating: displacements in um, velocities in um * omega_max,
  // the generator states (sin, cos, 1) and the torque O(1). The exponential is accurate normwise,
  // so without this the O(1) forcing columns would pollute the 1e-7 m displacements.
  Vector11 scale;
  scale << 1e-6, 1e-6, 1e-6, 1e-6 * w_max, 1e-6 * w_max, 1e-6 * w_max, 1.0, 1.0, 1.0, 1.0,
      1.0 / output_interval;
  // Balancing as an elementwise factor, (D^-1 X D)_rc = X_rc scale_c / scale_r: no dense product.
  const Matrix11 to_balanced = scale.cwiseInverse() * scale.transpose();

  for (int i = 0; i < 6; ++i) scale7_[i] = scale[i];
  scale7_[6] = scale[kU];
  propagators_.resize(n);
  k1_.resize(n);
  kc_.resize(n);
  backlash_offset_.resize(n);
  piece_begin_.assign(1, 0);
  tail_begin_.assign(1, 0);
  node_count_.resize(n);
  // Node propagators kept per mesh period: at most kMaxStoredNodes (every node_stride_-th node).
  node_stride_ =
      static_cast<int>(std::max(1.0, std::ceil(period / h_max * 1.05 / kMaxStoredNodes)));
  // What torqueStepResponse needs (node products, per-piece operators) only where the torque can
  // step inside an interval: the model's own input (the node) or a step profile.
  torque_steps_ = held_ || spec.torque.kind == TorqueProfile::Kind::kSteps;
  // The augmented matrix is [[state 6x6, forcing 6x5], [0, generator 5x5]]: the generator rows
  // (sin, cos, 1, u, u') never read the state, and so do Omega, its exponentials and their
  // products.
  std::vector<BlockTriangular<6, 5>> step_exps;  // one interval's Magnus steps, balanced units
  for (long j = 0; j < n; ++j) buildInterval(j, kinks, h_max, scale, to_balanced, step_exps);
  if (tabulate_settling && preload_force_ > 0.0) tabulateSettling(excitation, kinks, period);
}

void PeriodicExponentialPropagator::buildInterval(long j, const std::vector<double>& kinks,
                                                  double h_max, const Vector11& scale,
                                                  const Matrix11& to_balanced,
                                                  std::vector<BlockTriangular<6, 5>>& step_exps) {
  const double a = t0_ + j * interval_, b = a + interval_;
  MeshInstant mj;
  rig().at(a, mj);
  k1_[j] = mj.k_drive;
  kc_[j] = mj.k_back;
  backlash_offset_[j] = mj.backlash;
  std::vector<double> cuts = {a};
  for (auto it = std::upper_bound(kinks.begin(), kinks.end(), a); it != kinks.end() && *it < b;
       ++it) {
    if (*it - cuts.back() > 1e-12 * interval_) cuts.push_back(*it);
  }
  if (b - cuts.back() <= 1e-12 * interval_) cuts.pop_back();
  cuts.push_back(b);
  BlockTriangular<6, 5> phi = BlockTriangular<6, 5>::identity();
  step_exps.clear();
  for (std::size_t c = 0; c + 1 < cuts.size(); ++c)
    magnusPiece(cuts[c], cuts[c + 1] - cuts[c], h_max, to_balanced, step_exps, phi);
  propagators_[j] = phi.dense().cwiseQuotient(to_balanced).topRows<9>();  // back to physical units
  storeTails(step_exps, scale);
  node_count_[j] = static_cast<int>(step_exps.size());
  piece_begin_.push_back(static_cast<int>(pieces_.size()));
  tail_begin_.push_back(static_cast<int>(tails_.size()));
}

void PeriodicExponentialPropagator::magnusPiece(double start, double len, double h_max,
                                                const Matrix11& to_balanced,
                                                std::vector<BlockTriangular<6, 5>>& step_exps,
                                                BlockTriangular<6, 5>& phi) {
  using Blocks = BlockTriangular<6, 5>;
  const int steps = std::max(1, static_cast<int>(std::ceil(len / h_max)));
  const double h = len / steps;
  pieces_.push_back({start, h, steps, static_cast<int>(step_exps.size())});
  // A(t) is linear in t inside a piece (it ends on every table node and switch), A0 + tau A1
  // from two interior points (no switch at either end read on its wrong side), so the
  // 4th-order Magnus step with Gauss points t1, t2 = tau + (1/2 -+ sqrt(3)/6) h (Blanes, Casas,
  // Oteo & Ros 2009, eq. 4.4), Omega = h/2 (A(t1) + A(t2)) + sqrt(3) h^2/12 [A(t2), A(t1)], is
  // h A(tau + h/2) + h^3/12 [A1, A0]: one commutator per piece, none per step.
  const double ta = len / 3.0, tb = 2.0 * len / 3.0;
  const Matrix11 aa = systemMatrix(start + ta), ab = systemMatrix(start + tb);
  const Matrix11 a1 = (ab - aa) / (tb - ta), a0 = aa - ta * a1;
  // Parameters that pass validation can still overflow the system matrix (a mesh damping of
  // 1e307 over a gram): refused by name here, where the blocks would otherwise turn NaN.
  if (!aa.allFinite() || !ab.allFinite()) {
    throwInvalid(
        "system matrix", (aa.allFinite() ? ab : aa).cwiseAbs().maxCoeff(),
        "overflows at t = " + formatValue(start) + " s: the parameters are beyond double range");
  }
  const Matrix11 commutator = a1.lazyProduct(a0) - a0.lazyProduct(a1);
  // The generator rows never read the state (systemMatrix), so A0, A1 and [A1, A0] have a zero
  // lower-left block and blockTriangularExp may ignore it; checked once per piece.
  if (!a0.bottomLeftCorner<5, 6>().isZero(0.0) || !a1.bottomLeftCorner<5, 6>().isZero(0.0) ||
      !commutator.bottomLeftCorner<5, 6>().isZero(0.0)) {
    throw std::logic_error("exponential set-up: the forcing generator's rows read the state");
  }
  if (torque_steps_) piece_operators_.push_back(pieceOperators(aa, ab, len));
  for (int s = 0; s < steps; ++s) {
    const Matrix11 omega = h * (a0 + ((s + 0.5) * h) * a1) + (h * h * h / 12.0) * commutator;
    step_exps.push_back(
        blockTriangularExp(Blocks::fromDense(omega.cwiseProduct(to_balanced))));  // balanced units
    phi = step_exps.back() * phi;
    ++magnus_steps_;
  }
}

void PeriodicExponentialPropagator::storeTails(const std::vector<BlockTriangular<6, 5>>& step_exps,
                                               const Vector11& scale) {
  // Phi(b, node) backwards from the end, kept at the nodes stride, 2 stride, ... and the last.
  const int m = static_cast<int>(step_exps.size());
  const int kept = torque_steps_ ? (m + node_stride_ - 1) / node_stride_ : 0;
  tails_.resize(tails_.size() + kept);
  if (!torque_steps_) return;
  // Only the state rows: the torque response needs no TE or torque row.
  Eigen::Matrix<double, 6, 11> tail = Eigen::Matrix<double, 6, 11>::Identity();
  for (int node = m; node >= 1; --node) {
    if (node == m || node % node_stride_ == 0) {
      Tail& out = tails_[tail_begin_.back() + (node + node_stride_ - 1) / node_stride_ - 1];
      // Back to physical units: d (rows) tail d^-1 (columns).
      for (int c = 0; c < 7; ++c) {
        const int col = c < 6 ? c : static_cast<int>(kU);
        for (int r = 0; r < 6; ++r) out(r, c) = scale[r] * tail(r, col) / scale[col];
      }
    }
    // [T_x, T_y] [[E_x, E_y], [0, E_z]] = [T_x E_x, T_x E_y + T_y E_z]
    const BlockTriangular<6, 5>& e = step_exps[node - 1];
    Eigen::Matrix<double, 6, 5> right = tail.leftCols<6>() * e.y;
    right.noalias() += tail.rightCols<5>() * e.z;
    tail.leftCols<6>() = (tail.leftCols<6>() * e.x).eval();
    tail.rightCols<5>() = right;
  }
}

void PeriodicExponentialPropagator::tabulateSettling(const RigExcitation& excitation,
                                                     const std::vector<double>& kinks,
                                                     double period) {
  // The stiffness over one period: uniformly, and on both sides of every switch and table node.
  std::vector<double> times;
  for (int i = 0; i < 128; ++i) times.push_back(t0_ + period * i / 128.0);
  for (double t : kinks) {
    times.push_back(t - 1e-9 * period);
    times.push_back(t + 1e-9 * period);
  }
  std::sort(times.begin(), times.end());
  const std::size_t n = times.size();
  std::vector<double> k1(n), kc(n);
  for (std::size_t i = 0; i < n; ++i) {
    MeshInstant m;
    excitation.at(times[i], m);
    k1[i] = m.k_drive;
    kc[i] = m.k_back;
  }
  const double gain = swingGain(period);
  settle_gain_ = gain;
  // Held mesh force F with both flanks loaded at every phase: the static deflection
  // delta = F / (k1 + k_c) and its distance to the thresholds (the back path lifts at
  // delta = F_p / k_c, the drive flank at delta = -F_p / k1; AntiBacklashMesh::flankContact). Where
  // the swing that a step J of the static deflection starts can reach a threshold (distance below
  // kSettleMargin gain J) a flank may lift and land again between two samples, which the regime
  // check at the samples cannot see; so may it where F leaves both flanks loaded at some phase.
  // Those forces are marked. Grid: log-spaced in |F| / F_p from 1e-3 to 1e4, both signs.
  const double fp = preload_force_;
  const int per_sign = 240;
  std::vector<double> forces = {0.0};
  for (int i = 0; i < per_sign; ++i) {
    const double f = fp * std::pow(10.0, -3.0 + 7.0 * i / (per_sign - 1));
    forces.push_back(f);
    forces.push_back(-f);
  }
  std::sort(forces.begin(), forces.end());
  // What does not depend on the force, once per phase: the stiffness sum and the thresholds
  // F_p / k_c, F_p / k1 (one operation each, so the table is bit for bit what evaluating them per
  // force gives, with two divisions fewer per force and phase).
  bool stiff_everywhere = true;
  std::vector<double> sum(n), back_threshold(n), drive_threshold(n);
  for (std::size_t i = 0; i < n; ++i) {
    stiff_everywhere = stiff_everywhere && k1[i] > 0.0 && kc[i] > 0.0;
    sum[i] = k1[i] + kc[i];
    back_threshold[i] = fp / kc[i];
    drive_threshold[i] = fp / k1[i];
  }
  std::vector<double> delta(n), margin(n);
  for (double f : forces) {
    bool ok = stiff_everywhere;
    for (std::size_t i = 0; i < n && ok; ++i) {
      ok = AntiBacklashMesh::flankContact(f, k1[i], kc[i], fp) == FlankContact::kBoth;
      delta[i] = f / sum[i];
      margin[i] = std::min(back_threshold[i] - delta[i], delta[i] + drive_threshold[i]);
    }
    for (std::size_t i = 0; i < n && ok; ++i) {
      const double jump = std::abs(delta[i] - delta[i == 0 ? n - 1 : i - 1]);  // the period wraps
      ok = margin[i] > kSettleMargin * gain * jump;
    }
    settle_force_.push_back(f);
    settle_ok_.push_back(ok ? 1 : 0);
  }
}

double PeriodicExponentialPropagator::swingGain(double period) const {
  // gain: how far the mesh deflection can swing past its new static value, per unit of a step of
  // that static value, with both flanks loaded: a tooth switch steps the static deflection by J
  // (the shafts' static positions depend on the force alone, so the step is J on the torsional
  // coordinate x), and from rest at the old static state the deflection moves as
  // delta - delta_new = c e^{A t} (J e_x) = J sum_k (c v_k) e^{lambda_k t} (w_k e_x), bounded by
  // J sum_k |c v_k| |w_k e_x| (A's modes v_k, the rows w_k of V^-1; c reads delta = x + x_p - x_g).
  // The largest over 16 phases (the modes change little with the phase; 16 decompositions, not one
  // per sample).
  double gain = 0.0;
  for (int i = 0; i < 16; ++i) {
    const Matrix6 a = systemMatrix(t0_ + period * (i + 0.5) / 16.0).topLeftCorner<6, 6>();
    const Eigen::EigenSolver<Matrix6> es(a);
    if (es.info() != Eigen::Success) {
      gain = INFINITY;
      break;
    }
    const Eigen::Matrix<std::complex<double>, 6, 6> v = es.eigenvectors(), w = v.inverse();
    double g = 0.0;
    for (int k = 0; k < 6; ++k) g += std::abs(v(2, k) + v(0, k) - v(1, k)) * std::abs(w(k, 2));
    gain = std::isfinite(g) ? std::max(gain, g) : INFINITY;
  }
  return gain;
}

bool PeriodicExponentialPropagator::contactsSettle(double torque) const {
  if (settle_force_.empty()) return true;  // not tabulated, or an ordinary gear
  // The held mesh force (the drive force of the torsional coordinate's equilibrium).
  const double f = mean_force_ + torque_gain_ * (torque - torque_mean_);
  if (!std::isfinite(f)) return false;
  const auto it = std::lower_bound(settle_force_.begin(), settle_force_.end(), f);
  const std::size_t hi = std::min<std::size_t>(static_cast<std::size_t>(it - settle_force_.begin()),
                                               settle_force_.size() - 1);
  const std::size_t lo = hi > 0 ? hi - 1 : 0;
  return settle_ok_[lo] && settle_ok_[hi];  // both neighbours on the grid
}

PeriodicExponentialPropagator::PieceOperators PeriodicExponentialPropagator::pieceOperators(
    const Matrix11& at_third, const Matrix11& at_two_thirds, double length) const {
  // The system matrix on the state and the torque slot, balanced, is linear in t inside a piece
  // (the pieces end on every table node and switch): A(start + tau) = A0 + tau A1, from the
  // constructor's two interior samples (at a third and two thirds of the piece, so that no switch
  // at either end is evaluated on its wrong side).
  const auto restricted = [this](const Matrix11& full) {
    static constexpr int kIndex[7] = {kXp, kXg, kX, kVp, kVg, kV, kU};
    Matrix7 out;
    for (int r = 0; r < 7; ++r)
      for (int c = 0; c < 7; ++c) out(r, c) = full(kIndex[r], kIndex[c]) * scale7_[c] / scale7_[r];
    return out;
  };
  const double ta = length / 3.0, tb = 2.0 * length / 3.0;
  const Matrix7 aa = restricted(at_third), ab = restricted(at_two_thirds);
  PieceOperators ops;
  ops.a1 = (ab - aa) / (tb - ta);
  ops.a0 = aa - ta * ops.a1;
  ops.commutator = ops.a1 * ops.a0 - ops.a0 * ops.a1;
  return ops;
}

PeriodicExponentialPropagator::Vector7 PeriodicExponentialPropagator::magnusStepOnTorque(
    const PieceOperators& ops, double tau, double h, const Vector7& v) const {
  // The constructor's 4th-order Magnus step over [tau, tau + h] of a piece applied to a vector of
  // the state and the torque slot only. That subspace is invariant: no TE generator row (sin, cos,
  // 1) reads the state or the torque, and the torque slot's own row reads only u', zero for a
  // step. So the 7x7 restriction of Omega (commutator included, as the rows outside add nothing to
  // it) acts alone. With A linear in the piece, the Gauss points t1, t2 = tau + (1/2 -+ sqrt(3)/6)
  // h give Omega = h/2 (A(t1) + A(t2)) + sqrt(3) h^2/12 [A(t2), A(t1)] = h A(tau + h/2) + h^3/12
  // [A1, A0]. exp(Omega) v is summed as its Taylor series on the vector, in balanced units where
  // |Omega| is about h omega_max <= the step factor: to 1e-17 of the sum within some 25 terms,
  // matrix-vector products instead of a matrix exponential.
  const Matrix7 omega =
      h * (ops.a0 + (tau + 0.5 * h) * ops.a1) + (h * h * h / 12.0) * ops.commutator;
  Vector7 term = v.cwiseQuotient(scale7_), sum = term;
  for (int n = 1; n < 60; ++n) {
    term = omega * term / static_cast<double>(n);
    sum += term;
    if (term.cwiseAbs().maxCoeff() <= 1e-17 * sum.cwiseAbs().maxCoeff()) break;
  }
  return sum.cwiseProduct(scale7_);
}

State6 PeriodicExponentialPropagator::torqueStepResponse(long k, double offset) const {
  if (!torque_steps_) {
    throw InvalidInput(
        "torque step response: this propagator's torque cannot step (neither the model's input nor "
        "a step "
        "profile), so its node products were not built");
  }
  requireFinite("offset", offset);
  if (offset < 0.0 || offset > interval_ * (1.0 + 1e-12)) {
    throwInvalid("offset", offset,
                 "must lie in the output interval [0, " + formatValue(interval_) + "] s");
  }
  const long n = static_cast<long>(propagators_.size());
  const int j = static_cast<int>(((k % n) + n) % n);
  const double t = t0_ + j * interval_ + offset;  // the instant, in the first mesh period
  // The step holding t: its piece (the last whose start is <= t) and its place in the piece.
  int p = piece_begin_[j];
  while (p + 1 < piece_begin_[j + 1] && pieces_[p + 1].start <= t) ++p;
  const MagnusPiece& piece = pieces_[p];
  const int local =
      std::clamp(static_cast<int>(std::floor((t - piece.start) / piece.h)), 0, piece.steps - 1);
  const int m = node_count_[j];
  int node = piece.first_node + local + 1;  // the node that ends the step holding t
  const double step_end = piece.start + (local + 1) * piece.h;
  // Unit torque state at t (no displacement, velocity or TE), carried to that node exactly...
  Vector7 v = Vector7::Zero();
  v[6] = 1.0;
  if (step_end - t > 0.0)
    v = magnusStepOnTorque(piece_operators_[p], t - piece.start, step_end - t, v);
  // ... and on to the next kept node (node_stride_ > 1 only for very slow meshes).
  while (node < m && node % node_stride_ != 0) {
    int q = piece_begin_[j];
    while (q + 1 < piece_begin_[j + 1] && pieces_[q + 1].first_node <= node) ++q;
    const MagnusPiece& next = pieces_[q];
    v = magnusStepOnTorque(piece_operators_[q], (node - next.first_node) * next.h, next.h, v);
    ++node;
  }
  return tails_[tail_begin_[j] + (node + node_stride_ - 1) / node_stride_ - 1] * v;
}

PeriodicExponentialPropagator::Matrix11 PeriodicExponentialPropagator::systemMatrix(
    double t) const {
  MeshInstant m;
  rig().at(t, m);  // stiffness, preload and backlash: the drive force enters through the u columns
  const GearRotorParameters& p = model_.parameters();
  const double ks = m.k_drive + m.k_back, cs = p.mesh_damping;
  const bool anti_backlash = m.k_back > 0.0 || m.preload_force > 0.0;
  // Mesh force F = ks delta + cs delta' (both flanks closed: F_p cancels) or k1 (delta - b) + c
  // delta' (ordinary gear on its drive flank), delta = x + x_p - x_g - A sin, delta' = v + v_p -
  // v_g - A w cos.
  Eigen::Matrix<double, 1, 11> f = Eigen::Matrix<double, 1, 11>::Zero();
  f[kXp] = ks;
  f[kXg] = -ks;
  f[kX] = ks;
  f[kVp] = cs;
  f[kVg] = -cs;
  f[kV] = cs;
  f[kSin] = -ks * te_amplitude_;
  f[kCos] = -cs * te_amplitude_ * te_omega_;
  if (!anti_backlash) f[kOne] = -m.k_drive * m.backlash;
  Matrix11 a = Matrix11::Zero();
  a(kXp, kVp) = a(kXg, kVg) = a(kX, kV) = 1.0;
  a.row(kVp) = -f / p.pinion_mass;
  a(kVp, kXp) -= p.bearing_stiffness[0] / p.pinion_mass;
  a(kVp, kVp) -= p.bearing_damping[0] / p.pinion_mass;
  a.row(kVg) = f / p.gear_mass;
  a(kVg, kXg) -= p.bearing_stiffness[1] / p.gear_mass;
  a(kVg, kVg) -= p.bearing_damping[1] / p.gear_mass;
  const double ms = model_.equivalentMass();
  a.row(kV) = -f / ms;
  a(kV, kOne) += mean_force_ / ms;
  a(kV, kU) += torque_gain_ / ms;
  a(kSin, kCos) = te_omega_;
  a(kCos, kSin) = -te_omega_;
  a(kU, kUdot) = 1.0;
  return a;
}

bool PeriodicExponentialPropagator::linearRegime(int j,
                                                 const Eigen::Matrix<double, 9, 1>& z) const {
  const GearRotorParameters& p = model_.parameters();
  const double delta = z[kX] + z[kXp] - z[kXg] - te_amplitude_ * z[kSin];
  const double rate = z[kV] + z[kVp] - z[kVg] - te_amplitude_ * te_omega_ * z[kCos];
  const double k1 = k1_[j], kc = kc_[j], fp = preload_force_;
  if (kc > 0.0 || fp > 0.0) {
    const double c1 = p.mesh_damping * k1 / (k1 + kc), c2 = p.mesh_damping - c1;
    const double s1 = fp + k1 * delta, s2 = fp - kc * delta;
    const double t1 = s1 + c1 * rate, t2 = s2 - c2 * rate;
    return s1 > 0.0 && s2 > 0.0 && t1 >= 0.0 && t1 <= 2.0 * s1 && t2 >= 0.0 && t2 <= 2.0 * s2;
  }
  const double g = delta - backlash_offset_[j];
  const double total = k1 * g + p.mesh_damping * rate;
  return g > 0.0 && total >= 0.0 && total <= 2.0 * k1 * g;
}

double PeriodicExponentialPropagator::estimatedSetupSteps(const GearRotorModel& model,
                                                          const RigExcitation& excitation,
                                                          double t0, double step_factor) {
  requirePositive("magnus_step_factor", step_factor);
  return fastestRate(model, excitation, t0) / (step_factor * excitation.meshFrequency());
}

Matrix6 PeriodicExponentialPropagator::monodromy() const {
  // The state block of each interval propagator does not depend on the forcing columns.
  Matrix6 phi = Matrix6::Identity();
  for (const Propagator& p : propagators_) phi = p.block<6, 6>(0, 0) * phi;
  return phi;
}

PeriodicExponentialPropagator::Augmented PeriodicExponentialPropagator::augment(
    double t, const State6& y) const {
  Augmented z;
  z.head<6>() = y;
  z[kSin] = std::sin(te_omega_ * t + te_phase_);
  z[kCos] = std::cos(te_omega_ * t + te_phase_);
  z[kOne] = 1.0;
  return z;
}

bool PeriodicExponentialPropagator::step(long k, Augmented& z, double torque_k, double torque_next,
                                         const State6* added) const {
  const long n = static_cast<long>(propagators_.size());
  // The state must start in the linear regime too: one that starts with a flank lifted and ends,
  // under the closed regime's propagator, inside it would otherwise pass (the node hands such a
  // state over from a dopri5 interval; at -1 N m on the seed servo that costs 0.68 of the TE).
  if (!linearRegime(static_cast<int>(((k % n) + n) % n), z)) return false;
  const double mean = torque_mean_;
  Eigen::Matrix<double, 11, 1> w;
  w.head<9>() = z;
  w[kU] = torque_k - mean;
  w[kUdot] = (torque_next - torque_k) / interval_;
  Augmented next;
  next.noalias() = propagators_[((k % n) + n) % n].lazyProduct(w);  // as in run() (its comment)
  if (added) next.head<6>() += *added;
  if (!next.allFinite() || next.head<3>().cwiseAbs().maxCoeff() > divergence_limit_) {
    throw UnstableIntegration(
        "integrator exponential: displacement beyond the divergence limit at sample " +
        std::to_string(k + 1));
  }
  if (!linearRegime(static_cast<int>((((k + 1) % n) + n) % n), next)) return false;
  z = next;
  return true;
}

Eigen::Matrix<double, 9, 1> PeriodicExponentialPropagator::withTorqueSteps(
    long k, int j, Vector11& w, double before, double t_next, IntegrationStats& st) const {
  // The torque held from the interval's start, plus each step's size times the response to a unit
  // step at its instant (exact: the system is linear).
  const TorqueProfile& torque = rig().spec().torque;
  w[kUdot] = 0.0;
  Eigen::Matrix<double, 9, 1> z_next;
  z_next.noalias() = propagators_[j].lazyProduct(w);
  for (const auto& step : torque.steps) {
    if (step.first > t_next - interval_ && step.first <= t_next) {
      z_next.head<6>() +=
          (step.second - before) * torqueStepResponse(k, step.first - (t_next - interval_));
      before = step.second;
      ++st.events;
    }
  }
  return z_next;
}

State6 PeriodicExponentialPropagator::handOver(double t_k, const State6& y_k, double t_end,
                                               const Observer& observe,
                                               const IntegratorOptions& fallback,
                                               IntegrationStats& st,
                                               IntegrationStats* stats) const {
  IntegrationStats rest;
  bool first = true;
  const State6 y_end = integrate(
      model_, IntegratorMethod::kDopri5, fallback, t_k, y_k, t_end, interval_,
      [&](double t, const State6& y) {
        if (!first && observe) observe(t, y);
        first = false;
      },
      &rest);
  st.steps += rest.steps;
  st.rhs_evaluations += rest.rhs_evaluations;
  st.events += rest.events;
  st.fallbacks = 1;
  st.fallback_from = t_k;
  if (stats) *stats = st;
  return y_end;
}

State6 PeriodicExponentialPropagator::run(const State6& y0, double t_end, const Observer& observe,
                                          const IntegratorOptions& fallback,
                                          IntegrationStats* stats) const {
  if (!y0.allFinite()) throw InvalidInput("initial state: contains a non-finite value");
  const double span = t_end - t0_;
  const long k_end = std::lround(span / interval_);
  if (k_end < 0 || std::abs(span - k_end * interval_) > 1e-9 * std::max(interval_, span)) {
    throwInvalid("t_end", t_end,
                 "must be t0 plus a whole number of output intervals " + formatValue(interval_));
  }
  IntegrationStats st;
  const TorqueProfile& torque = rig().spec().torque;
  Eigen::Matrix<double, 9, 1> z;
  z.head<6>() = y0;
  z[kSin] = std::sin(te_omega_ * t0_ + te_phase_);
  z[kCos] = std::cos(te_omega_ * t0_ + te_phase_);
  z[kOne] = 1.0;
  if (observe) observe(t0_, y0);
  const int n = static_cast<int>(propagators_.size());
  double u = torqueAt(t0_) - torque.mean;
  Vector11 w;
  // The interval's propagator: k mod n carried rather than divided out at every sample. Each
  // product is Eigen's lazyProduct: 9 + 1 + 11 is above Eigen's threshold for coefficient-based
  // products, so operator* took its GEMV kernel, whose call costs more than the product at this
  // size (69 -> 41-52 ns a sample in a scratch loop). With Eigen 3.4 and SSE/AVX the results are
  // bit for bit those of the GEMV kernel: rows 0-7 are computed in packets in the same column
  // order, and row 8 (summed in another order, without packets) is the constant generator row,
  // exactly e_8. Without vectorisation the last bits could differ (an independent review measured
  // it).
  int j = 0;
  for (long k = 0; k < k_end; ++k) {
    const double t_next = t0_ + (k + 1) * interval_;
    const double u_next = torqueAt(t_next) - torque.mean;
    w.head<9>() = z;
    w[kU] = u;
    w[kUdot] = (u_next - u) / interval_;
    Eigen::Matrix<double, 9, 1> z_next;
    if (torque.kind == TorqueProfile::Kind::kSteps &&
        stepInside(torque, t_next - interval_, t_next)) {
      z_next = withTorqueSteps(k, j, w, u + torque.mean, t_next, st);
    } else {
      z_next.noalias() = propagators_[j].lazyProduct(w);
    }
    const int j_next = j + 1 == n ? 0 : j + 1;
    if (!linearRegime(j_next, z_next)) {
      // A contact opened: dopri5 takes over from the last sample in the linear regime.
      return handOver(t0_ + k * interval_, z.head<6>(), t_end, observe, fallback, st, stats);
    }
    z = z_next;
    u = u_next;
    j = j_next;
    ++st.steps;
    if (!z.allFinite() || z.head<3>().cwiseAbs().maxCoeff() > fallback.divergence_limit) {
      throw UnstableIntegration("integrator exponential diverged at t = " + formatValue(t_next) +
                                " s (no bounded response)");
    }
    if (observe) observe(t_next, z.head<6>());
  }
  if (stats) *stats = st;
  return z.head<6>();
}

}  // namespace drivetrain_stiffness

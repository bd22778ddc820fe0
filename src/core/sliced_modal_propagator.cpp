#include "drivetrain_stiffness/core/sliced_modal_propagator.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/turns.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

using Complex = std::complex<double>;

double norm2(Complex z) { return z.real() * z.real() + z.imag() * z.imag(); }

/// n / d written out (a complex division calls __divdc3; |d| is far from overflow here).
Complex divide(Complex n, Complex d) {
  const double inv = 1.0 / norm2(d);
  return {(n.real() * d.real() + n.imag() * d.imag()) * inv,
          (n.imag() * d.real() - n.real() * d.imag()) * inv};
}

/// phi_1(z) = (e^z - 1) / z by its Taylor series, for |z| < 0.05: sum_k z^k / (k + 1)!, stopped
/// once a term is below 1e-17 (|phi_1| > 0.97 there, so that is below half an ulp of the sum); at
/// most 8 terms are needed (0.05^8 / 9! < 1e-16), 16 allowed.
[[gnu::always_inline]] inline Complex phi1Series(Complex z) {
  // 1/k as constants: a division per term would cost more than the rest of the term.
  static constexpr double kInverse[18] = {
      0.0,     1.0,      1.0 / 2,  1.0 / 3,  1.0 / 4,  1.0 / 5,  1.0 / 6,  1.0 / 7,  1.0 / 8,
      1.0 / 9, 1.0 / 10, 1.0 / 11, 1.0 / 12, 1.0 / 13, 1.0 / 14, 1.0 / 15, 1.0 / 16, 1.0 / 17};
  double sr = 1.0, si = 0.0, tr = 1.0,
         ti = 0.0;  // sum and term, written out (no NaN-recovery branch)
  for (int k = 2; k <= 17; ++k) {
    const double r = (tr * z.real() - ti * z.imag()) * kInverse[k];
    ti = (tr * z.imag() + ti * z.real()) * kInverse[k];
    tr = r;
    sr += tr;
    si += ti;
    if (std::fabs(tr) + std::fabs(ti) < 1e-17) break;
  }
  return {sr, si};
}

/// E(lambda, mu, h) = integral_0^h e^{lambda (h - s)} e^{mu s} ds, given e^{lambda h} and e^{mu h}.
/// The magnitude test and the division are written out: std::abs and std::norm of a complex call
/// hypot in libstdc++, and a complex division calls __divdc3 (Annex G's scaling), which together
/// cost as much as the exponentials of a slice step; |mu - lambda| is far from overflow here
/// (the modes are below 1e7 rad/s).
[[gnu::always_inline]] inline Complex forcedIntegral(Complex lambda, Complex mu, double h,
                                                     Complex e_lambda, Complex e_mu) {
  const Complex d = mu - lambda, z = d * h;
  // The difference quotient loses about eps / |z| to cancellation (the two exponentials agree to
  // |z|): below |z| = 0.05 the series takes over, so E is accurate to 5e-15 either way. A larger
  // threshold would send most slices at high speed (|lambda h| ~ 0.1 at 6000 rpm) to the series,
  // which costs three times the quotient.
  if (norm2(z) < 0.0025)
    return h * e_lambda * phi1Series(z);  // = (e^{mu h} - e^{lambda h}) / (mu - lambda)
  return divide(e_mu - e_lambda, d);
}

/// The infinity norm (largest row sum of magnitudes) of a complex matrix, each magnitude as
/// sqrt(re^2 + im^2): the general decomposition's condition check. Eigen's cwiseAbs() of a complex
/// matrix calls hypot per coefficient; the check compares with 1e8, so hypot's last-bit accuracy
/// and overflow guard (the coefficients are scaled to about 1) buy nothing. (The seeded path writes
/// its own, with the balancing scales and the conjugate pairs: decomposeSeeded.)
template <typename Matrix>
double infinityNorm(const Matrix& m) {
  double largest = 0.0;
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    double sum = 0.0;
    for (Eigen::Index c = 0; c < m.cols(); ++c) sum += std::sqrt(norm2(m(i, c)));
    largest = std::max(largest, sum);
  }
  return largest;
}

/// max_k |lambda_k|, with std::abs's own rounding (hypot), which the step cut where the regime
/// bound fails (an eighth of the fastest mode's period) reads: hypot is taken only for the
/// eigenvalues whose squared magnitude is within rounding of the largest, and once for an exact
/// conjugate of one already taken, instead of six times.
template <typename Vector>
double largestMagnitude(const Vector& lambda) {
  double top = 0.0;
  for (Eigen::Index k = 0; k < lambda.size(); ++k) top = std::max(top, norm2(lambda[k]));
  double largest = 0.0;
  for (Eigen::Index k = 0; k < lambda.size(); ++k) {
    if (norm2(lambda[k]) < top * (1.0 - 1e-12)) continue;
    bool repeated = false;  // |conj z| = |z| bit for bit: hypot ignores the signs
    for (Eigen::Index l = 0; l < k && !repeated; ++l)
      repeated = lambda[l] == lambda[k] || lambda[l] == std::conj(lambda[k]);
    if (!repeated) largest = std::max(largest, std::abs(lambda[k]));
  }
  return largest;
}

}  // namespace

SlicedModalPropagator::SlicedModalPropagator(const GearRotorParameters& p,
                                             std::shared_ptr<const SlicedMesh> slices,
                                             double te_amplitude, double backlash)
    : slices_(std::move(slices)), te_amplitude_(te_amplitude), backlash_(backlash) {
  if (!slices_) throw InvalidInput("sliced propagator: no sliced mesh");
  requireNonNegative("transmission_error_amplitude", te_amplitude);
  requireNonNegative("backlash", backlash);
  // The three usual regimes' rules now; the others (stiffened flanks, both unloaded) when first
  // met. The slices of each regime are sized when a parameter set first uses them.
  for (MeshRegime r : {MeshRegime::kBothFlanks, MeshRegime::kDriveFlank, MeshRegime::kBackFlank}) {
    conditions_[static_cast<std::size_t>(r)].resize(static_cast<std::size_t>(slices_->size()));
  }
  setParameters(p);
  for (MeshRegime r : {MeshRegime::kBothFlanks, MeshRegime::kDriveFlank, MeshRegime::kBackFlank}) {
    activeSlices(r).resize(static_cast<std::size_t>(slices_->size()));
  }
}

void SlicedModalPropagator::setParameters(const GearRotorParameters& p) {
  p.validate();
  if (p.bearing_clearance[0] > 0.0 || p.bearing_clearance[1] > 0.0) {
    throw InvalidInput(
        "exact propagation: bearing clearance makes the model nonlinear at every crossing; use "
        "dopri5");
  }
  p_ = p;
  m_s_ = p.equivalentMass();
  // The set of these parameters: a kept one as it was, or the longest unused one (never used
  // first) emptied for them. Its slots keep their last modes as seeds.
  DecompositionKey key;
  key.bearing_stiffness = p.bearing_stiffness;
  key.bearing_damping = p.bearing_damping;
  key.mesh_damping = p.mesh_damping;
  key.pinion_mass = p.pinion_mass;
  key.gear_mass = p.gear_mass;
  key.mesh_mass = m_s_;
  // A never-used set has last_used 0, every used one more, so the least last_used is the first
  // never-used set while there is one.
  std::size_t found = sets_.size(), victim = 0;
  for (std::size_t i = 0; i < sets_.size(); ++i) {
    if (sets_[i].last_used > 0 && sets_[i].key == key) found = i;
    if (sets_[i].last_used < sets_[victim].last_used) victim = i;
  }
  const std::size_t before = active_;
  if (found < sets_.size()) {
    if (found != active_) ++kept_sets_reused_;
    active_ = found;
  } else {
    KeptSet& set = sets_[victim];
    for (auto& regime : set.slices) {
      for (Slice& s : regime) s.ready = false;
    }
    set.key = key;
    active_ = victim;
  }
  if (active_ != before) previous_ = static_cast<int>(before);
  sets_[active_].last_used = ++use_clock_;
  // The contact rules depend on the mesh damping (flankLaw, meshTerms; the slices, the preload
  // force, the backlash and the TE amplitude are the propagator's own): tabulated here, read at
  // every step, no allocation (the tables keep their size). Remade only when that damping changed:
  // a bearing-stiffness change, which under a rippling load above the anti-backlash knee comes
  // hundreds of times a second, keeps them (all regimes' tables took 13 % of such a replay).
  if (!(p.mesh_damping == conditions_mesh_damping_)) {
    for (int r = 0; r < kRegimes; ++r) {
      std::vector<RegimeConditions>& table = conditions_[static_cast<std::size_t>(r)];
      for (std::size_t j = 0; j < table.size(); ++j)
        table[j] = makeConditions(static_cast<MeshRegime>(r), static_cast<int>(j));
    }
    conditions_mesh_damping_ = p.mesh_damping;
  }
  // trace(M^-1 K) = (k_b1 + k) / m_p + (k_b2 + k) / m_g + k / m_s at the stiffest mesh k of any
  // regime (both flanks: k1 + k_c), which bounds every omega^2 of the undamped problem.
  double k = 0.0;
  for (int j = 0; j < slices_->size(); ++j) k = std::max(k, slices_->k1(j) + slices_->kChain(j));
  const double trace = (p.bearing_stiffness[0] + k) / p.pinion_mass +
                       (p.bearing_stiffness[1] + k) / p.gear_mass + k / m_s_;
  fastest_period_bound_ =
      trace > 0.0 ? kTwoPi / std::sqrt(trace) : std::numeric_limits<double>::infinity();
}

void SlicedModalPropagator::tabulateRegimeConditions(MeshRegime r) const {
  // Once per regime and propagator (not in the steady state of a run): sized, its rules tabulated
  // for the parameters of now (setParameters keeps every allocated table up to date).
  const std::size_t n = static_cast<std::size_t>(slices_->size());
  std::vector<RegimeConditions>& table = conditions_[static_cast<std::size_t>(r)];
  table.resize(n);
  for (std::size_t j = 0; j < n; ++j) table[j] = makeConditions(r, static_cast<int>(j));
}

SlicedModalPropagator::FlankLaw SlicedModalPropagator::flankLaw(int flank, int j) const {
  // GearRotorModel::forces, each flank's spring force s = k g and its spring-and-damper force
  // t = k g + c g' written in the mesh deflection delta (docs/model.md eqs M1-M3):
  //  - anti-backlash drive flank, g1 = delta + F_p / k1: s1 = F_p + k1 delta, damper c1 = c k1 /
  //  (k1 + k_c);
  //  - anti-backlash back path, g2 = F_p / k_c - delta: s2 = F_p - k_c delta, damper c2 = c - c1 on
  //  -delta';
  //  - ordinary gear with backlash b, drive flank g = delta - b: s = -k1 b + k1 delta, damper c;
  //  - ordinary gear, back flank g = -delta - b: s = -k1 b - k1 delta, damper c on -delta'.
  const SlicedMesh& m = *slices_;
  const double k1 = m.k1(j), kc = m.kChain(j);
  if (m.antiBacklash()) {
    const double fp = m.mesh().preloadForce(), c1 = driveFlankDamping(j);
    if (flank == 0) return {fp, k1, c1, k1 > 0.0};
    return {fp, -kc, -(p_.mesh_damping - c1), kc > 0.0};
  }
  const double sign = flank == 0 ? 1.0 : -1.0;
  return {-k1 * backlash_, sign * k1, sign * p_.mesh_damping, k1 > 0.0};
}

SlicedModalPropagator::MeshTerms SlicedModalPropagator::meshTerms(MeshRegime r, int j) const {
  // The mesh force F = F1 - F2 (drive flank minus back path) in a linear regime, each flank's force
  // 0 (unloaded), t = s + beta delta' (loaded) or 2 s (stiffened, its damper clipped at twice the
  // spring: GearRotorModel's contact rule), with s and t from flankLaw. Both loaded on the
  // anti-backlash gear: F = (k1 + k_c) delta + c delta' (F_p cancels); the back path lifted (above
  // the knee): F = k1 delta + c1 delta' + F_p; an ordinary gear on its drive flank:
  // F = k1 (delta - b) + c delta'. The constant goes to the forcing, the rest to A.
  MeshTerms t{0.0, 0.0, 0.0};
  const FlankState states[2] = {driveState(r), backState(r)};
  for (int flank = 0; flank < 2; ++flank) {
    if (states[flank] == FlankState::kUnloaded) continue;
    const FlankLaw law = flankLaw(flank, j);
    const double sign = flank == 0 ? 1.0 : -1.0;  // F = F1 - F2
    const double times = states[flank] == FlankState::kStiffened ? 2.0 : 1.0;
    t.stiffness += sign * times * law.alpha;
    t.constant += sign * times * law.c0;
    if (states[flank] == FlankState::kLoaded) t.damping += sign * law.beta;
  }
  return t;
}

double SlicedModalPropagator::driveFlankDamping(int j) const {
  // The mesh damping shared as the stiffness is (GearRotorModel::forces): c1 = c k1 / (k1 + k_c).
  const double k1 = slices_->k1(j), kc = slices_->kChain(j);
  return k1 + kc > 0.0 ? p_.mesh_damping * k1 / (k1 + kc) : 0.0;
}

SlicedModalPropagator::RegimeConditions SlicedModalPropagator::makeConditions(MeshRegime r,
                                                                              int j) const {
  // The contact rules of GearRotorModel::forces for regime r, each a force linear in the mesh
  // deflection and its rate, c0 + alpha delta + beta delta', that must be > 0 (strict) or >= 0.
  // With s and t a flank's spring and spring-and-damper forces (flankLaw), the rule of
  // GearRotorModel's contact (Modelica ElastoBacklash: the damper never pulls, never more than
  // doubles the spring) splits every state of the flank into three linear pieces:
  //   loaded:     s > 0, t >= 0, 2 s - t >= 0   (force t)
  //   stiffened:  s > 0, t - 2 s > 0            (force 2 s)
  //   unloaded:   -s >= 0, or -t > 0            (force 0: open, or its damper clipped at zero)
  // which cover every state once. inRegime evaluates them at a state, regimeMargin bounds them over
  // a step: one list.
  RegimeConditions out;
  auto rule = [&](double c0, double alpha, double beta, bool strict) {
    // The rule's force scale for regimeMargin: its constant and the TE amplitude's share.
    const double scale = std::fabs(c0) + std::fabs(alpha) * te_amplitude_ + 1e-300;
    return ContactCondition{c0,          alpha, beta, std::fabs(alpha), std::fabs(beta),
                            1.0 / scale, strict};
  };
  auto add = [&](const ContactCondition& c) { out.c[static_cast<std::size_t>(out.n++)].first = c; };
  const FlankState states[2] = {driveState(r), backState(r)};
  for (int flank = 0; flank < 2; ++flank) {
    const FlankLaw f = flankLaw(flank, j);
    if (!f.exists) {  // no stiffness: the flank can only be unloaded (GearRotorModel: g = -1)
      if (states[flank] != FlankState::kUnloaded) out.possible = false;
      continue;
    }
    switch (states[flank]) {
      case FlankState::kLoaded:
        add(rule(f.c0, f.alpha, 0.0, true));       // s > 0
        add(rule(f.c0, f.alpha, f.beta, false));   // t >= 0
        add(rule(f.c0, f.alpha, -f.beta, false));  // 2 s - t >= 0
        break;
      case FlankState::kStiffened:
        add(rule(f.c0, f.alpha, 0.0, true));       // s > 0
        add(rule(-f.c0, -f.alpha, f.beta, true));  // t - 2 s > 0
        break;
      case FlankState::kUnloaded: {
        Clause& c = out.c[static_cast<std::size_t>(out.n++)];
        c.first = rule(-f.c0, -f.alpha, 0.0, false);      // -s >= 0
        c.second = rule(-f.c0, -f.alpha, -f.beta, true);  // -t > 0
        c.either = true;
        break;
      }
    }
  }
  // No mesh stiffness (both flanks unloaded): the mesh coordinate is a free mass, whose double
  // zero eigenvalue has no eigenbasis. dopri5 takes those moments.
  out.terms = meshTerms(r, j);
  if (!(out.terms.stiffness > 0.0)) out.possible = false;
  return out;
}

Matrix6 SlicedModalPropagator::systemMatrix(MeshRegime r, int j) const {
  // y' = [[0, I], [-M^-1 K, -M^-1 C]] y with M = diag(m_p, m_g, m_s) and K, C the shared
  // mesh-and-bearing assembly (meshBearingMatrix, the modal analysis' and the scenes').
  const MeshTerms t = meshTerms(r, j);
  const Eigen::Vector3d m_inv(1.0 / p_.pinion_mass, 1.0 / p_.gear_mass, 1.0 / m_s_);
  Matrix6 a = Matrix6::Zero();
  a.topRightCorner<3, 3>().setIdentity();
  a.bottomLeftCorner<3, 3>() =
      -(m_inv.asDiagonal() * meshBearingMatrix(t.stiffness, p_.bearing_stiffness));
  a.bottomRightCorner<3, 3>() =
      -(m_inv.asDiagonal() * meshBearingMatrix(t.damping, p_.bearing_damping));
  return a;
}

const SlicedModalPropagator::Slice& SlicedModalPropagator::slice(MeshRegime r, int j) const {
  std::vector<Slice>& cache = activeSlices(r);
  // The first time this set meets the regime (bounded: sets times regimes).
  if (cache.empty()) cache.resize(static_cast<std::size_t>(slices_->size()));
  Slice& s = cache[static_cast<std::size_t>(j)];
  if (s.ready) return s;
  ++decompositions_;
  // Seeds for the three modes: a neighbouring slice already decomposed with these parameters (its
  // mesh stiffness differs by one slice's step), else this slice's modes under the parameters
  // before the last change (the set active before it), else this slot's last modes under any.
  // Crossing order makes the neighbour behind the motion the usual seed.
  const int n = static_cast<int>(cache.size());
  const Slice& below = cache[static_cast<std::size_t>(j == 0 ? n - 1 : j - 1)];
  const Slice& above = cache[static_cast<std::size_t>(j + 1 == n ? 0 : j + 1)];
  bool done = false;
  if (below.ready && below.has_upper) done = decomposeSeeded(r, j, s, below.upper);
  if (!done && above.ready && above.has_upper) done = decomposeSeeded(r, j, s, above.upper);
  if (!done && previous_ >= 0) {
    const std::vector<Slice>& before =
        sets_[static_cast<std::size_t>(previous_)].slices[static_cast<std::size_t>(r)];
    if (!before.empty() && before[static_cast<std::size_t>(j)].has_upper) {
      done = decomposeSeeded(r, j, s, before[static_cast<std::size_t>(j)].upper);
    }
  }
  if (!done && s.has_upper) done = decomposeSeeded(r, j, s, s.upper);
  if (!done) decomposeGeneral(r, j, s);
  s.fastest = largestMagnitude(s.lambda);
  for (int k = 0; k < 6; ++k) s.deflection[k] = s.weight[k] * (s.v(0, k) - s.v(1, k) + s.v(2, k));
  s.ready = true;
  return s;
}

namespace {

// A slice's modes as the quadratic eigenvalue problem Q(lambda) u = 0 with
// Q = lambda^2 M + lambda C + K, M = diag(m_p, m_g, m_s), and K, C = diag(bearing, bearing, 0) +
// (mesh) g g^T, g = (1, -1, 1) (meshBearingMatrix): the eigenvalues of A = [[0, I], [-M^-1 K,
// -M^-1 C]] are the roots of det Q, and its eigenvectors are (u, lambda u) (Tisseur and
// Meerbergen, "The quadratic eigenvalue problem", SIAM Review 43(2), 2001, section 3.4). With the
// bearing parts diagonal, Q = D(lambda) + sigma(lambda) g g^T, D_i = lambda^2 m_i + lambda c_i +
// k_i, sigma = lambda c_s + k_s, and by the matrix determinant lemma
//   det Q = D_0 D_1 D_2 + sigma (D_1 D_2 + D_0 D_2 + D_0 D_1),
// a closed form that Newton's method polishes from a seed in a few steps (the mesh stiffness
// moves little from one slice to the next).
struct Pencil {
  std::array<double, 3> mass, kb, cb;
  double ks, cs;
  /// D_i(l) and D_i'(l).
  void diag(Complex l, std::array<Complex, 3>& d, std::array<Complex, 3>& dd) const {
    for (int i = 0; i < 3; ++i) {
      d[i] = (l * mass[i] + cb[i]) * l + kb[i];
      dd[i] = 2.0 * mass[i] * l + cb[i];
    }
  }
};

// Newton on det Q from each seed, in place; false where one does not converge to a root with a
// positive imaginary part.
bool polishRoots(const Pencil& q, std::array<Complex, 3>& seeds) {
  const double ks = q.ks, cs = q.cs;
  std::array<Complex, 3> d, dd;
  for (Complex& l : seeds) {
    bool converged = false;
    for (int it = 0; it < 40 && !converged; ++it) {
      q.diag(l, d, dd);
      const Complex sigma = l * cs + ks;
      const Complex pair_sum = d[1] * d[2] + d[0] * d[2] + d[0] * d[1];
      const Complex f = d[0] * d[1] * d[2] + sigma * pair_sum;
      const Complex df = dd[0] * d[1] * d[2] + d[0] * dd[1] * d[2] + d[0] * d[1] * dd[2] +
                         cs * pair_sum +
                         sigma * (dd[1] * d[2] + d[1] * dd[2] + dd[0] * d[2] + d[0] * dd[2] +
                                  dd[0] * d[1] + d[0] * dd[1]);
      const double den = norm2(df);
      if (!(den > 0.0) || !std::isfinite(den)) return false;
      const Complex step((f.real() * df.real() + f.imag() * df.imag()) / den,
                         (f.imag() * df.real() - f.real() * df.imag()) / den);
      l -= step;
      converged = norm2(step) <=
                  1e-28 * norm2(l);  // |step| <= 1e-14 |lambda|: the next step is at rounding
    }
    if (!converged || !(l.imag() > 0.0)) return false;
  }
  return true;
}

// The roots are distinct and, with their conjugates, the whole spectrum: sum = trace(A), product =
// det(A), which no set that repeats a root or misses one reproduces.
bool wholeSpectrum(const Pencil& q, const std::array<Complex, 3>& seeds,
                   const Eigen::Matrix3d& k_matrix) {
  double scale = 0.0, re_sum = 0.0, log_product = 0.0;
  for (int k = 0; k < 3; ++k) {
    scale += std::sqrt(norm2(seeds[k]));
    re_sum += 2.0 * seeds[k].real();
    log_product += std::log(norm2(seeds[k]));
    for (int l = 0; l < k; ++l) {
      if (norm2(seeds[k] - seeds[l]) <= 1e-12 * norm2(seeds[k])) return false;
    }
  }
  const std::array<double, 3>& mass = q.mass;
  const double trace = -((q.cb[0] + q.cs) / mass[0] + (q.cb[1] + q.cs) / mass[1] + q.cs / mass[2]);
  const double det_k = k_matrix.determinant();
  if (!(det_k > 0.0) || std::abs(re_sum - trace) > 1e-9 * scale ||
      std::abs(log_product - std::log(det_k / (mass[0] * mass[1] * mass[2]))) > 1e-9) {
    return false;
  }
  return true;
}

// The eigenbasis' condition in balanced coordinates, ||D^-1 V|| ||V^-1 D|| in the infinity norm,
// D = diag(1, 1, 1, w, w, w), the general path's usability rule. Column k + 3 of V and row k + 3
// of V^-1 are the conjugates of column and row k, whose magnitudes are the same bits: each
// magnitude is taken once and the sums run in infinityNorm's order, so the condition is
// infinityNorm's to the bit with half its square roots.
double seededCondition(const Eigen::Matrix<Complex, 6, 6>& v,
                       const Eigen::Matrix<Complex, 6, 6>& v_inv, double w_ref) {
  double v_norm = 0.0, v_inv_norm = 0.0;
  for (int i = 0; i < 6; ++i) {
    double a[3];
    for (int c = 0; c < 3; ++c) a[c] = std::sqrt(norm2(v(i, c)));
    const double sum =
        a[0] + a[1] + a[2] + a[0] + a[1] + a[2];  // left to right, as infinityNorm sums
    v_norm = std::max(v_norm, sum / (i < 3 ? 1.0 : w_ref));
  }
  for (int i = 0; i < 3; ++i) {
    double sum = 0.0;
    for (int c = 0; c < 6; ++c) sum += std::sqrt(norm2(v_inv(i, c))) * (c < 3 ? 1.0 : w_ref);
    v_inv_norm = std::max(v_inv_norm, sum);
  }
  return v_norm * v_inv_norm;
}

}  // namespace

bool SlicedModalPropagator::decomposeSeeded(MeshRegime r, int j, Slice& s,
                                            std::array<Complex, 3> seeds) const {
  // The roots of det Q (Pencil) by Newton, accepted only if every root converged and they are the
  // whole spectrum; otherwise the caller falls back to the general eigensolver. Cost: about a
  // tenth of Eigen's EigenSolver plus the inverse of V.
  const MeshTerms t = meshTerms(r, j);
  const double ks = t.stiffness, cs = t.damping;
  const Pencil q{{p_.pinion_mass, p_.gear_mass, m_s_},
                 {p_.bearing_stiffness[0], p_.bearing_stiffness[1], 0.0},
                 {p_.bearing_damping[0], p_.bearing_damping[1], 0.0},
                 ks,
                 cs};
  const std::array<double, 3>& mass = q.mass;
  const std::array<double, 3>& cb = q.cb;
  const double g[3] = {1.0, -1.0, 1.0};
  if (!polishRoots(q, seeds)) return false;
  const Eigen::Matrix3d k_matrix = meshBearingMatrix(ks, p_.bearing_stiffness);
  if (!wholeSpectrum(q, seeds, k_matrix)) return false;
  // Eigenvectors, in the layout step() expects: k = 0..2 the modes with positive imaginary part
  // (weight 2), k = 3..5 their conjugates (weight 0, kept for monodromy()). The null vector is
  // u_i = g_i prod_{l != i} D_l (a column of adj Q for this rank-one update, up to scale). M, C
  // and K are symmetric, so the left eigenvector of A is (lambda M u + C u, M u) and the row of
  // A's inverse eigenvector matrix is that over u^T (2 lambda M + C) u = u^T Q'(lambda) u
  // (Tisseur and Meerbergen, section 3.4).
  const double w_ref = std::sqrt(std::max(
      1.0, (k_matrix.cwiseAbs().array().colwise() / Eigen::Array3d(mass[0], mass[1], mass[2]))
               .maxCoeff()));
  std::array<Complex, 3> d, dd;
  for (int k = 0; k < 3; ++k) {
    const Complex l = seeds[k];
    q.diag(l, d, dd);
    CVector v;
    Complex gu = 0.0;
    for (int i = 0; i < 3; ++i) {
      v[i] = g[i] * d[(i + 1) % 3] * d[(i + 2) % 3];
      gu += g[i] * v[i];
    }
    double big = 0.0;
    for (int i = 0; i < 3; ++i) big = std::max(big, norm2(v[i]));
    if (!(big > 0.0) || !std::isfinite(big)) return false;
    for (int i = 0; i < 3; ++i) v[i] /= std::sqrt(big);
    gu /= std::sqrt(big);
    for (int i = 0; i < 3; ++i) v[i + 3] = l * v[i];
    Complex denominator = cs * gu * gu;  // u^T (2 lambda M + C) u
    for (int i = 0; i < 3; ++i) denominator += dd[i] * v[i] * v[i];
    const double den = norm2(denominator);
    if (!(den > 0.0) || !std::isfinite(den)) return false;
    const Complex inv_den = std::conj(denominator) / den;
    Eigen::Matrix<Complex, 1, 6> row;
    for (int i = 0; i < 3; ++i) {
      const Complex cu = cb[i] * v[i] + cs * g[i] * gu;  // (C u)_i
      row[i] = (l * mass[i] * v[i] + cu) * inv_den;
      row[i + 3] = mass[i] * v[i] * inv_den;
    }
    s.lambda[k] = l;
    s.lambda[k + 3] = std::conj(l);
    s.v.col(k) = v;
    s.v.col(k + 3) = v.conjugate();
    s.v_inv.row(k) = row;
    s.v_inv.row(k + 3) = row.conjugate();
    s.weight[k] = 2.0;
    s.weight[k + 3] = 0.0;
    s.upper[k] = l;
  }
  const double condition = seededCondition(s.v, s.v_inv, w_ref);
  s.usable = std::isfinite(condition) && condition < 1e8;
  Eigen::Matrix<double, 6, 1> e_f, e_v;
  e_f << 0.0, 0.0, 0.0, -1.0 / mass[0], 1.0 / mass[1], -1.0 / mass[2];
  e_v << 0.0, 0.0, 0.0, 0.0, 0.0, 1.0 / mass[2];
  s.force_dir = s.v_inv * e_f.cast<Complex>();
  s.drive_dir = s.v_inv * e_v.cast<Complex>();
  s.has_upper = true;
  return true;
}

void SlicedModalPropagator::decomposeGeneral(MeshRegime r, int j, Slice& s) const {
  const Matrix6 a = systemMatrix(r, j);
  // Balance displacements against velocities (scale omega_ref = sqrt(max |A_vx|)) so that the
  // eigenvectors are well scaled; A = D A_b D^-1, V = D V_b, V^-1 = V_b^-1 D^-1.
  const double w_ref = std::sqrt(std::max(1.0, a.block<3, 3>(3, 0).cwiseAbs().maxCoeff()));
  Eigen::Matrix<double, 6, 1> d;
  d << 1.0, 1.0, 1.0, w_ref, w_ref, w_ref;
  const Matrix6 a_b = d.cwiseInverse().asDiagonal() * a * d.asDiagonal();
  const Eigen::EigenSolver<Matrix6> eig(a_b, true);
  ++general_decompositions_;
  s.usable = eig.info() == Eigen::Success;
  if (s.usable) {
    const CMatrix v_b = eig.eigenvectors();
    const Eigen::PartialPivLU<CMatrix> lu(v_b);
    const CMatrix v_b_inv = lu.inverse();
    // A defective (critically damped) or nearly defective pair has no usable eigenbasis: dopri5
    // takes it.
    const double condition = infinityNorm(v_b) * infinityNorm(v_b_inv);
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
        const bool pair =
            s.weight[j] != 0.0 &&
            std::abs(s.lambda[j] - std::conj(s.lambda[k])) <= 1e-12 * std::abs(s.lambda[k]) &&
            (s.v.col(j) - s.v.col(k).conjugate()).cwiseAbs().maxCoeff() <=
                1e-12 * s.v.col(k).cwiseAbs().maxCoeff();
        if (pair) {
          s.weight[k] = 2.0;
          s.weight[j] = 0.0;
          break;
        }
      }
      if (s.weight[k] != 2.0)
        s.usable = false;  // a complex eigenvalue without its conjugate: not a real system's
    }
  }
  s.has_upper = false;
  if (s.usable && std::count(s.weight.begin(), s.weight.end(), 2.0) == 3) {
    int i = 0;
    for (int k = 0; k < 6; ++k) {
      if (s.weight[k] == 2.0)
        s.upper[i++] = s.lambda[k].imag() > 0.0 ? s.lambda[k] : std::conj(s.lambda[k]);
    }
    s.has_upper = true;
  }
}

void SlicedModalPropagator::prepare(const Slice& s, MeshRegime r, int j, const State6& y,
                                    Complex e_theta0, double w, double drive_force,
                                    Piece& out) const {
  const MeshTerms& t = conditions(r, j).terms;  // tabulated: this runs at every step
  // Forcing in modal coordinates: U sin(theta) + W w cos(theta) + G, written as
  // P e^{i w s} + Q e^{-i w s} + G with sin x = (e^{ix} - e^{-ix}) / 2i, cos x = (e^{ix} + e^{-ix})
  // / 2.
  const double u = -t.stiffness * te_amplitude_, wc = -t.damping * te_amplitude_ * w;
  const Complex p_coef = e_theta0 * Complex(0.5 * wc, -0.5 * u),
                q_coef = std::conj(e_theta0) * Complex(0.5 * wc, 0.5 * u);
  const Complex iw(0.0, w);
  out.n = 0;
  for (int k = 0; k < 6; ++k) {
    if (s.weight[k] == 0.0) continue;  // the conjugate of a mode already counted twice
    const int i = out.n++;
    out.k[i] = k;
    double er = 0.0, ei = 0.0;  // row k of V^-1 y (complex times real)
    for (int c = 0; c < 6; ++c) {
      er += s.v_inv(k, c).real() * y[c];
      ei += s.v_inv(k, c).imag() * y[c];
    }
    out.eta0[i] = Complex(er, ei);
    out.force_p[i] = s.force_dir[k] * p_coef;
    out.force_q[i] = s.force_dir[k] * q_coef;
    out.force_g[i] = s.force_dir[k] * t.constant + s.drive_dir[k] * drive_force;
    // The particular solution (forced response) and the free part R = eta(0) - particular(0).
    const Complex lambda = s.lambda[k], d1 = iw - lambda, d2 = -iw - lambda;
    out.n1[i] = norm2(d1);
    out.n2[i] = norm2(d2);
    out.nl[i] = norm2(lambda);
    out.particular[i] = out.n1[i] > 0.0 && out.n2[i] > 0.0 && out.nl[i] > 0.0;
    if (!out.particular[i]) continue;
    out.pf[i] = divide(out.force_p[i], d1);
    out.qf[i] = divide(out.force_q[i], d2);
    out.gf[i] = divide(-out.force_g[i], lambda);
    out.r0[i] = out.eta0[i] - out.pf[i] - out.qf[i] - out.gf[i];
  }
}

void SlicedModalPropagator::advance(const Slice& s, const Piece& piece, double w, double h,
                                    Complex e_mu, State6& y) const {
  // eta(h) = e^{lambda h} R + P' e^{iwh} + Q' e^{-iwh} + G' (the particular form, no division), or
  // where some |mu - lambda| h < 0.05 the same by the forced integrals E with their phi_1 series
  // (the particular form would lose eps / |z| to cancellation there, as the quotient would).
  const Complex mu(0.0, w), e_mu_conj = std::conj(e_mu);
  State6 next = State6::Zero();
  for (int i = 0; i < piece.n; ++i) {
    const int k = piece.k[i];
    const Complex lambda = s.lambda[k];
    // e^{lambda h} as glibc's cexp computes it for Re(lambda h) <= 709 (always here: a passive
    // mode has Re lambda <= 0): exp of the real part times the sine and cosine of the imaginary
    // part, one sincos, without cexp's classification of the argument; the same bits (a review
    // compared 4e6 arguments with real parts in [-800, 1]), a few per cent of the crossing less.
    const double magnitude = std::exp(lambda.real() * h), angle = lambda.imag() * h;
    const Complex e_l(magnitude * std::cos(angle), magnitude * std::sin(angle));
    Complex eta;
    const double h2 = h * h;
    if (piece.particular[i] && piece.n1[i] * h2 >= 0.0025 && piece.n2[i] * h2 >= 0.0025 &&
        piece.nl[i] * h2 >= 0.0025) {
      eta = e_l * piece.r0[i] + piece.pf[i] * e_mu + piece.qf[i] * e_mu_conj + piece.gf[i];
    } else {
      eta = e_l * piece.eta0[i] + piece.force_p[i] * forcedIntegral(lambda, mu, h, e_l, e_mu) +
            piece.force_q[i] * forcedIntegral(lambda, -mu, h, e_l, e_mu_conj) +
            piece.force_g[i] * forcedIntegral(lambda, 0.0, h, e_l, 1.0);
    }
    // Re(v_k eta) only: the imaginary part would be dropped.
    const double weight = s.weight[k];
    for (int c = 0; c < 6; ++c)
      next[c] += weight * (s.v(c, k).real() * eta.real() - s.v(c, k).imag() * eta.imag());
  }
  y = next;
}

bool SlicedModalPropagator::inRegime(MeshRegime r, int j, const State6& y, Complex e_theta,
                                     double w) const {
  // The conditions of regime r at y, with the TE forcing's phase theta given as e_theta = e^{i
  // theta}.
  const RegimeConditions& rc = conditions(r, j);
  if (!rc.possible) return false;
  const double delta = y[2] + y[0] - y[1] - te_amplitude_ * e_theta.imag();
  const double rate = y[5] + y[3] - y[4] - te_amplitude_ * w * e_theta.real();
  const auto holds = [&](const ContactCondition& c) {
    const double force = c.c0 + c.alpha * delta + c.beta * rate;
    return c.strict ? force > 0.0 : force >= 0.0;  // NaN fails both
  };
  bool all = true;
  for (int i = 0; i < rc.n; ++i) {
    const Clause& c = rc.c[static_cast<std::size_t>(i)];
    all &= holds(c.first) || (c.either && holds(c.second));
  }
  return all;
}

std::optional<SlicedModalPropagator::MeshRegime> SlicedModalPropagator::regimeAt(int j,
                                                                                 const State6& y,
                                                                                 Complex e_theta,
                                                                                 double w) const {
  // Each flank's state from its forces (makeConditions' three pieces, which cover every finite
  // state once), then the regime's own test, which also refuses a regime without mesh stiffness.
  const double delta = y[2] + y[0] - y[1] - te_amplitude_ * e_theta.imag();
  const double rate = y[5] + y[3] - y[4] - te_amplitude_ * w * e_theta.real();
  if (!std::isfinite(delta) || !std::isfinite(rate)) return std::nullopt;
  FlankState states[2];
  for (int flank = 0; flank < 2; ++flank) {
    const FlankLaw f = flankLaw(flank, j);
    // The rules' own expressions, as inRegime evaluates them (c0 + alpha delta + beta rate, left to
    // right): 2 s - t >= 0 and t - 2 s > 0 are then exact negations of each other, where comparing
    // t with 2 s would disagree with them within an ulp and refuse both regimes.
    const double spring = f.c0 + f.alpha * delta, total = spring + f.beta * rate;
    const double spare = spring + (-f.beta) * rate;  // 2 s - t
    states[flank] = !f.exists || !(spring > 0.0) || total < 0.0 ? FlankState::kUnloaded
                    : spare >= 0.0                              ? FlankState::kLoaded
                                                                : FlankState::kStiffened;
  }
  const MeshRegime r = regimeOf(states[0], states[1]);
  if (!inRegime(r, j, y, e_theta, w))
    return std::nullopt;  // both unloaded: no linear propagation here
  return r;
}

double SlicedModalPropagator::regimeMargin(const Slice& s, MeshRegime r, int j, const Piece& piece,
                                           Complex e_theta0, double w) const {
  // A lower bound, over any step from the prepared state while the slice lasts, of every contact
  // rule of the regime (conditions(): forces c0 + alpha delta + beta delta' that must stay >= 0),
  // over the rule's scale. Per mode the exact solution is eta_k(t) = e^{lambda t} R_k + P'_k
  // e^{iwt}
  // + Q'_k e^{-iwt} + G'_k (prepare), and delta = Re sum_k w_k p_k eta_k - A sin(theta) with
  // p_k = g . u_k (u_k the displacement half of v_k, g = (1, -1, 1)); delta' takes lambda_k on the
  // free part and +-iw on the forced one. So each condition is a constant, decaying modes (each at
  // most its size at t = 0, as Re lambda < 0) and one sinusoid at w: constant - sum |modes| -
  // |sinusoid| bounds it below (|z| <= |Re z| + |Im z|, no hypot), here through an interval for
  // delta and a bound on |delta'| shared by the conditions. A positive bound proves the
  // contacts keep their state through the step, which the checks at the step's ends alone do not:
  // a mode at 60 kHz can lift a flank and put it back inside one slice at low speed.
  auto l1 = [](Complex z) { return std::fabs(z.real()) + std::fabs(z.imag()); };
  const Complex iw(0.0, w);
  // delta(t) in [delta_c - spread_d, delta_c + spread_d] and |delta'(t)| <= spread_r over the step.
  double delta_c = 0.0, spread_d = 0.0, spread_r = 0.0;
  Complex delta_sin = 0.0, rate_sin = 0.0;
  for (int i = 0; i < piece.n; ++i) {
    if (!piece.particular[i]) return -1.0;  // resonant or a zero eigenvalue: no bound
    const int k = piece.k[i];
    const Complex p = s.deflection[k];
    delta_c += (p * piece.gf[i]).real();
    const Complex pp = p * piece.pf[i], pq = p * piece.qf[i], free = p * piece.r0[i];
    delta_sin += pp + std::conj(pq);
    rate_sin += iw * pp + std::conj(-iw * pq);
    spread_d += l1(free);
    spread_r += l1(s.lambda[k] * free);
  }
  // The TE's own terms: -e = Re(i A e^{i theta}), -e' = Re(-A w e^{i theta}).
  delta_sin += Complex(0.0, te_amplitude_) * e_theta0;
  rate_sin += -te_amplitude_ * w * e_theta0;
  spread_d += l1(delta_sin);
  spread_r += l1(rate_sin);
  const RegimeConditions& rc = conditions(r, j);
  if (!rc.possible) return -1.0;
  const auto lower = [&](const ContactCondition& c) {
    const double bound = c.c0 + c.alpha * delta_c - c.abs_alpha * spread_d - c.abs_beta * spread_r;
    return bound * c.inverse_scale;  // the scale is positive: the sign is the bound's
  };
  double worst = std::numeric_limits<double>::infinity();
  for (int i = 0; i < rc.n; ++i) {
    const Clause& c = rc.c[static_cast<std::size_t>(i)];
    // Either rule keeping its sign through the step keeps the clause: the larger bound.
    worst = std::min(worst, c.either ? std::max(lower(c.first), lower(c.second)) : lower(c.first));
  }
  return worst;
}

bool SlicedModalPropagator::propagate(State6& y, double& phase, double f, double duration,
                                      double drive_force) const {
  State6 z = y;
  double p = phase;
  if (!(propagateLinear(z, p, f, duration, drive_force) >= duration)) return false;
  y = z;
  phase = p;
  return true;
}

double SlicedModalPropagator::propagateLinear(State6& y, double& phase, double f, double duration,
                                              double drive_force) const {
  if (!(duration >= 0.0) || !std::isfinite(f) || !std::isfinite(phase) ||
      !std::isfinite(drive_force))
    return 0.0;
  Walk k;
  k.z = y;
  k.whole = std::floor(phase);
  k.frac = phase - k.whole;
  k.remaining = duration;
  // The TE forcing's phasor e^{i 2 pi frac}: one sine and cosine where the call starts inside a
  // slice, then carried: a step that ends on a boundary takes the boundary's tabulated phasor, and
  // the phasor's advance over that step, e^{i w h} = e^{i 2 pi (boundary - frac)}, follows from the
  // two. A slice crossed whole thus costs no sine or cosine beyond its modes' exponentials.
  k.e_theta = std::polar(1.0, kTwoPi * k.frac);
  while (k.remaining > 0.0 && walkStep(k, f, drive_force)) {
  }
  // What was propagated goes back to the caller, up to where no linear regime holds.
  y = k.z;
  phase = k.whole + k.frac;
  return k.remaining > 0.0 ? duration - k.remaining : duration;
}

bool SlicedModalPropagator::takeRegime(Walk& k, double w) const {
  const std::optional<MeshRegime> found = regimeAt(k.j, k.z, k.e_theta, w);
  if (found) k.regime = *found;
  return found.has_value();
}

double SlicedModalPropagator::stepLength(const Walk& k, double f, double& next,
                                         bool& crossing) const {
  const SlicedMesh& m = *slices_;
  double h = k.remaining;
  next = k.frac + f * k.remaining;
  crossing = false;
  if (f != 0.0) {
    const double boundary = f > 0.0 ? m.end(k.j) : m.start(k.j);
    const double to_boundary = (boundary - k.frac) / f;
    if (to_boundary <= k.remaining) {
      h = to_boundary;
      next = boundary;  // exactly on it: the next piece starts in the next slice, no drift
      crossing = true;
    }
  }
  return h;
}

bool SlicedModalPropagator::walkStep(Walk& k, double f, double drive_force) const {
  const SlicedMesh& m = *slices_;
  const double w = kTwoPi * f;
  if (f < 0.0 && k.frac == 0.0) {  // backwards from a period boundary: the top of the period below
    k.whole -= 1.0;
    k.frac = 1.0;
  }
  if (k.j < 0) {  // the contacts the call starts with
    k.j = m.sliceAt(k.frac == 1.0 ? std::nextafter(1.0, 0.0) : k.frac, f < 0.0);
    if (!takeRegime(k, w)) return false;
  }
  const Slice& s = slice(k.regime, k.j);
  if (!s.usable) return false;
  double next;
  bool crossing;
  double h = stepLength(k, f, next, crossing);
  // The contacts must keep their state through the step, not only at its ends: where the bound
  // cannot show it, the step is cut to an eighth of the fastest mode's period, so that the checks
  // at the ends sample every oscillation that could lift a flank (a change missed between two of
  // them would be one that stays open for less than that).
  Piece& piece = piece_;
  prepare(s, k.regime, k.j, k.z, k.e_theta, w, drive_force, piece);
  if (regimeMargin(s, k.regime, k.j, piece, k.e_theta, w) <= 0.0) {
    const double h_check = s.fastest > 0.0 ? kTwoPi / (8.0 * s.fastest) : h;
    if (h_check < h) {
      h = h_check;
      next = k.frac + f * h;
      crossing = false;
      ++substeps_;
    }
  }
  const Complex e_end =
      crossing ? m.boundaryPhasor(f > 0.0 ? k.j + 1 : k.j) : k.e_theta * std::polar(1.0, w * h);
  advance(s, piece, w, h, e_end * std::conj(k.e_theta), k.z_end);
  if (!k.z_end.allFinite()) return false;
  const bool leaves = !inRegime(k.regime, k.j, k.z_end, e_end, w);
  if (leaves) {
    // A contact changed inside the step: located on this regime's exact solution, the state
    // just past the change goes on in the regime it is in there.
    if (++k.changes > kMaxChangesPerCall) return false;  // chatter: dopri5's to resolve
    Complex e_hi = e_end;
    const double hi = locateChange(s, piece, k.regime, k.j, k.e_theta, w, h, k.z, k.z_end, &e_hi);
    if (hi < h) {
      advance(s, piece, w, hi, e_hi * std::conj(k.e_theta), k.z);
      k.e_theta = e_hi;
      // Inside the slice, short of the boundary the step would have reached (kept there where
      // the change lies within rounding of it, so the next step's length is not negative).
      k.frac = std::clamp(k.frac + f * hi, m.start(k.j), m.end(k.j));
      k.remaining -= hi;
      ++events_;
      return takeRegime(k, w);
    }
    // At the step's very end (to the bisection's resolution): the step stands as it was.
  }
  return endStep(k, f, h, next, crossing, leaves, e_end);
}

bool SlicedModalPropagator::endStep(Walk& k, double f, double h, double next, bool crossing,
                                    bool leaves, Complex e_end) const {
  const int n = slices_->size();
  const double w = kTwoPi * f;
  k.z = k.z_end;
  k.e_theta = e_end;
  k.remaining = crossing || h < k.remaining ? k.remaining - h : 0.0;
  k.frac = next;
  if (k.frac >= 1.0) {
    k.whole += 1.0;
    k.frac -= 1.0;
  }
  if (crossing) {
    ++crossed_;
    // Right limit: the slice entered must also hold the contacts. Forwards it is the next slice
    // (the first of the next period after the last); backwards the one below (the top one of the
    // period below from the first), as sliceAt would find it. The stiffness steps there, so the
    // contacts may change on the boundary itself.
    k.j = f > 0.0 ? (k.j + 1 == n ? 0 : k.j + 1) : (k.j == 0 ? n - 1 : k.j - 1);
  }
  if ((leaves || crossing) && !inRegime(k.regime, k.j, k.z, k.e_theta, w)) {
    if (!takeRegime(k, w)) return false;
    ++events_;
  }
  return true;
}

double SlicedModalPropagator::regimeValue(MeshRegime r, int j, const State6& y, Complex e_theta,
                                          double w) const {
  // inRegime's conditions as one continuous number: the least clause, each rule's force over its
  // scale (an either-clause: the larger of its two rules). >= 0 where the contacts are r's (up to
  // the strict rules' equality, which inRegime decides).
  const RegimeConditions& rc = conditions(r, j);
  const double delta = y[2] + y[0] - y[1] - te_amplitude_ * e_theta.imag();
  const double rate = y[5] + y[3] - y[4] - te_amplitude_ * w * e_theta.real();
  const auto value = [&](const ContactCondition& c) {
    return (c.c0 + c.alpha * delta + c.beta * rate) * c.inverse_scale;
  };
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i < rc.n; ++i) {
    const Clause& c = rc.c[static_cast<std::size_t>(i)];
    least = std::min(least, c.either ? std::max(value(c.first), value(c.second)) : value(c.first));
  }
  return least;
}

double SlicedModalPropagator::locateChange(const Slice& s, const Piece& piece, MeshRegime r, int j,
                                           Complex e_theta, double w, double h, const State6& start,
                                           const State6& end, Complex* e_hi) const {
  // The first length out of regime r, bracketed by [lo, hi] (in r at lo = 0, out of it at hi = h)
  // to the resolution of 40 halvings (2^-40 of the step, itself at most an eighth of the fastest
  // mode's period where the bound cannot clear it), the contacts tested as at the step's ends.
  // Trial lengths by the Illinois variant of false position on regimeValue along the exact solution
  // (Dowell and Jarratt, BIT 11 (1971) 168: superlinear, order 1.44, bracketing), about eight
  // advances after the samples where bisection took forty, with halvings where it would not serve:
  //  - while the value at lo is at the rounding of the contact forces (kRoundingValue): a step
  //    that starts right after a change starts on the boundary of its regime (regimeValue
  //    ~1e-15), where false position tries lengths of 1e-19 s, at which the forces have not
  //    moved past their rounding and the test is noise (a landing taken for an immediate lift
  //    measured 1.1e-5 of the TE off dopri5 at 5.45 N m, 120 rpm);
  //  - whenever two trials have not halved the bracket (false position crawling from one side).
  // First the bracket: the earliest of kEventSamples equal lengths found out of r, and the one
  // before it. A state can leave r, come back and leave again within a step (a damper clipping
  // for a fraction of a microsecond as a flank lands: measured on the load_sweep bag), and a
  // search over the whole step may converge on the later change; the samples find the first one
  // unless an excursion lies wholly between two of them (an eighth of the step, itself at most an
  // eighth of the fastest mode's period where the bound cannot clear it).
  const double tol = std::ldexp(h, -kEventHalvings);
  double lo = 0.0, hi = h;
  double g_lo = std::max(regimeValue(r, j, start, e_theta, w), 0.0);
  double g_hi = std::min(regimeValue(r, j, end, *e_hi, w), 0.0);
  State6 z;
  for (int i = 1; i < kEventSamples; ++i) {
    const double t = h * i / kEventSamples;
    const Complex e_mu = std::polar(1.0, w * t);
    advance(s, piece, w, t, e_mu, z);
    const Complex e_t = e_theta * e_mu;
    const double g = regimeValue(r, j, z, e_t, w);
    if (!inRegime(r, j, z, e_t, w)) {
      hi = t;
      g_hi = std::min(g, 0.0);
      *e_hi = e_t;
      break;
    }
    lo = t;
    g_lo = std::max(g, 0.0);
  }
  double checked =
      2.0 *
      (hi - lo);  // the bracket's width two trials ago (the first trial may be false position)
  int kept = 0;   // +1: lo kept by the last trial, -1: hi kept (Illinois halves a value kept twice)
  for (int it = 0; it < 3 * kEventHalvings && hi - lo > tol; ++it) {
    bool halve = g_lo < kRoundingValue || !(g_lo - g_hi > 0.0);
    if (it % 2 == 0) {
      halve = halve || hi - lo > 0.5 * checked;
      checked = hi - lo;
    }
    double t = 0.5 * (lo + hi);
    if (!halve) {
      const double guess = lo + (hi - lo) * (g_lo / (g_lo - g_hi));
      // NaN where the values overflowed (a rule without constant or TE amplitude has a scale near
      // 1e-300): halve then; std::clamp would pass the NaN on.
      if (std::isfinite(guess)) t = std::clamp(guess, lo + 0.25 * tol, hi - 0.25 * tol);
    }
    const Complex e_mu = std::polar(1.0, w * t);
    advance(s, piece, w, t, e_mu, z);
    const Complex e_t = e_theta * e_mu;
    const double g = regimeValue(r, j, z, e_t, w);
    if (inRegime(r, j, z, e_t, w)) {
      lo = t;
      g_lo = std::max(g, 0.0);
      if (kept == -1) g_hi *= 0.5;
      kept = -1;
    } else {
      hi = t;
      g_hi = std::min(g, 0.0);
      *e_hi = e_t;
      if (kept == 1) g_lo *= 0.5;
      kept = 1;
    }
  }
  return hi;
}

Matrix6 SlicedModalPropagator::monodromy(double f) const { return monodromyIn(loadedRegime(), f); }

bool SlicedModalPropagator::loadedSliceMap(int j, double phase, double f, double h,
                                           AffineMap& out) const {
  const MeshRegime r = loadedRegime();
  const Slice& s = slice(r, j);
  if (!s.usable) return false;
  const double w = kTwoPi * f;
  const Complex e_theta = std::polar(1.0, kTwoPi * phase), e_mu = std::polar(1.0, w * h);
  // The forced part from rest without drive force, and the unit drive force's part as the same
  // with F_d = 1 less that: the solution propagateLinear advances a state by (prepare, advance).
  const State6 rest = State6::Zero();
  prepare(s, r, j, rest, e_theta, w, 0.0, piece_);
  advance(s, piece_, w, h, e_mu, out.forced);
  prepare(s, r, j, rest, e_theta, w, 1.0, piece_);
  advance(s, piece_, w, h, e_mu, out.drive);
  out.drive -= out.forced;
  // The homogeneous part, sum_k weight_k Re(v_k e^{lambda_k h} (V^-1)_k) (a conjugate pair's
  // weight 2 on one member): V e^{Lambda h} V^-1, real for a real system.
  out.phi.setZero();
  for (int k = 0; k < 6; ++k) {
    if (s.weight[k] == 0.0) continue;
    const Complex e_l = std::exp(s.lambda[k] * h);
    out.phi += s.weight[k] * ((s.v.col(k) * e_l) * s.v_inv.row(k)).real();
  }
  return out.phi.allFinite() && out.drive.allFinite() && out.forced.allFinite();
}

double SlicedModalPropagator::loadedSwingGain() const {
  // deflection[k] = weight_k (c v_k): a conjugate pair's two equal terms as twice one of them.
  double gain = 0.0;
  for (int i = 0; i < 16; ++i) {
    const Slice& s = slice(loadedRegime(), slices_->sliceAt((i + 0.5) / 16.0, false));
    if (!s.usable) return std::numeric_limits<double>::infinity();
    double g = 0.0;
    for (int k = 0; k < 6; ++k) g += std::abs(s.deflection[k]) * std::abs(s.v_inv(k, 2));
    gain = std::max(gain, g);
  }
  return gain;
}

bool SlicedModalPropagator::inLoadedRegime(const State6& y, double phase, double f) const {
  if (!std::isfinite(phase) || !std::isfinite(f)) return false;
  const double frac = wrapTurns(phase);
  const int j = slices_->sliceAt(frac, f < 0.0);
  return inRegime(loadedRegime(), j, y, std::polar(1.0, kTwoPi * frac), kTwoPi * f);
}

std::optional<Matrix6> SlicedModalPropagator::monodromy(double f, const State6& y,
                                                        double phase) const {
  requireFinite("mesh frequency", f);
  requireFinite("mesh phase", phase);
  // wrapTurns, as inLoadedRegime: phase - floor(phase) rounds to 1.0 for a phase just below an
  // integer (-1e-17), which sliceAt would clamp to the last slice where the period's first is
  // meant.
  const double frac = wrapTurns(phase);
  const int j = slices_->sliceAt(frac, f < 0.0);
  const Complex e_theta = std::polar(1.0, kTwoPi * frac);
  const std::optional<MeshRegime> r = regimeAt(j, y, e_theta, kTwoPi * f);
  if (!r) return std::nullopt;
  // A period-long map describes the motion only in the regimes a flank holds for a period: both
  // loaded, or one loaded and the other open. A stiffened flank (just landed) or a damper clipped
  // at zero (opening) is a moment, as is any state that the period map of its regime would
  // misdescribe: no margin there.
  if (*r != MeshRegime::kBothFlanks && *r != MeshRegime::kDriveFlank &&
      *r != MeshRegime::kBackFlank)
    return std::nullopt;
  const double delta = y[2] + y[0] - y[1] - te_amplitude_ * e_theta.imag();
  for (int flank = 0; flank < 2; ++flank) {
    const FlankState state = flank == 0 ? driveState(*r) : backState(*r);
    const FlankLaw law = flankLaw(flank, j);
    if (state == FlankState::kUnloaded && law.exists && law.c0 + law.alpha * delta > 0.0)
      return std::nullopt;
  }
  return monodromyIn(*r, f);
}

Matrix6 SlicedModalPropagator::monodromyIn(MeshRegime r, double f) const {
  requireFinite("mesh frequency", f);
  if (f == 0.0) throw InvalidInput("monodromy: the mesh must turn (mesh frequency 0)");
  Matrix6 phi = Matrix6::Identity();
  const int n = slices_->size();
  for (int i = 0; i < n; ++i) {
    const int j = f > 0.0 ? i : n - 1 - i;
    const Slice& s = slice(r, j);
    const double tau = (slices_->end(j) - slices_->start(j)) / std::abs(f);
    CVector e;
    for (int k = 0; k < 6; ++k) e[k] = std::exp(s.lambda[k] * tau);
    phi = (s.v * e.asDiagonal() * s.v_inv).real() * phi;
  }
  return phi;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/core/dynamics/sliced_slice_tables.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"

namespace drivetrain_stiffness {
namespace sliced {
namespace {

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
// of V^-1 are the conjugates of column and row k, whose magnitudes are equal to the bit: each
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

// Mode k (0..2) of the seeded decomposition from its root l, and its conjugate k + 3, into s:
// eigenvalues, eigenvectors, rows of V^-1, weights and seed; false where the null vector or the
// normalisation is degenerate.
bool seededMode(const Pencil& q, int k, Complex l, Slice& s) {
  const std::array<double, 3>& mass = q.mass;
  const std::array<double, 3>& cb = q.cb;
  const double cs = q.cs;
  const double g[3] = {1.0, -1.0, 1.0};
  std::array<Complex, 3> d, dd;
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
  return true;
}

}  // namespace

void SliceTables::select(const GearRotorParameters& p, double m_s) {
  p_ = p;
  m_s_ = m_s;
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
}

const Slice& SliceTables::slice(MeshRegime r, int j, const ContactRules& rules) const {
  std::vector<Slice>& cache = activeSlices(r);
  // The first time this set meets the regime (bounded: sets times regimes).
  if (cache.empty()) cache.resize(static_cast<std::size_t>(rules.slices().size()));
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
  if (below.ready && below.has_upper) done = decomposeSeeded(r, j, s, below.upper, rules);
  if (!done && above.ready && above.has_upper) done = decomposeSeeded(r, j, s, above.upper, rules);
  if (!done && previous_ >= 0) {
    const std::vector<Slice>& before =
        sets_[static_cast<std::size_t>(previous_)].slices[static_cast<std::size_t>(r)];
    if (!before.empty() && before[static_cast<std::size_t>(j)].has_upper) {
      done = decomposeSeeded(r, j, s, before[static_cast<std::size_t>(j)].upper, rules);
    }
  }
  if (!done && s.has_upper) done = decomposeSeeded(r, j, s, s.upper, rules);
  if (!done) decomposeGeneral(r, j, s, rules);
  s.fastest = largestMagnitude(s.lambda);
  for (int k = 0; k < 6; ++k) s.deflection[k] = s.weight[k] * (s.v(0, k) - s.v(1, k) + s.v(2, k));
  s.ready = true;
  return s;
}

bool SliceTables::decomposeSeeded(MeshRegime r, int j, Slice& s, std::array<Complex, 3> seeds,
                                  const ContactRules& rules) const {
  // The roots of det Q (Pencil) by Newton, accepted only if every root converged and they are the
  // whole spectrum; otherwise the caller falls back to the general eigensolver. Cost: about a
  // tenth of Eigen's EigenSolver plus the inverse of V.
  const MeshTerms t = rules.meshTerms(r, j);
  const double ks = t.stiffness, cs = t.damping;
  const Pencil q{{p_.pinion_mass, p_.gear_mass, m_s_},
                 {p_.bearing_stiffness[0], p_.bearing_stiffness[1], 0.0},
                 {p_.bearing_damping[0], p_.bearing_damping[1], 0.0},
                 ks,
                 cs};
  const std::array<double, 3>& mass = q.mass;
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
  for (int k = 0; k < 3; ++k) {
    if (!seededMode(q, k, seeds[k], s)) return false;
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

void SliceTables::decomposeGeneral(MeshRegime r, int j, Slice& s, const ContactRules& rules) const {
  const Matrix6 a = systemMatrix(r, j, rules);
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

Matrix6 SliceTables::systemMatrix(MeshRegime r, int j, const ContactRules& rules) const {
  // y' = [[0, I], [-M^-1 K, -M^-1 C]] y with M = diag(m_p, m_g, m_s) and K, C the shared
  // mesh-and-bearing assembly (meshBearingMatrix, the modal analysis' and the scenes').
  const MeshTerms t = rules.meshTerms(r, j);
  const Eigen::Vector3d m_inv(1.0 / p_.pinion_mass, 1.0 / p_.gear_mass, 1.0 / m_s_);
  Matrix6 a = Matrix6::Zero();
  a.topRightCorner<3, 3>().setIdentity();
  a.bottomLeftCorner<3, 3>() =
      -(m_inv.asDiagonal() * meshBearingMatrix(t.stiffness, p_.bearing_stiffness));
  a.bottomRightCorner<3, 3>() =
      -(m_inv.asDiagonal() * meshBearingMatrix(t.damping, p_.bearing_damping));
  return a;
}

}  // namespace sliced
}  // namespace drivetrain_stiffness

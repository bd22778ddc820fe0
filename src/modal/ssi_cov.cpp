#include "drivetrain_stiffness/modal/ssi_cov.hpp"

#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness::modal {
namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXcd;
using Eigen::VectorXd;

/// Lag covariances R_k = 1/N sum_t y_{t+k} y_t^T, k = p+1..p+lags, over the columns
/// t0..t0+n-1, stacked as l x l blocks side by side (Peeters & De Roeck 1999, "covariance-driven
/// SSI"; docs/vibration.md, "SSI-COV").
MatrixXd lagCovariances(const MatrixXd& y, long t0, long n, int lags, int p) {
  const long l = y.rows();
  // Channel-major copy: each R_k(a, b) is then one contiguous dot product (vectorised), where a
  // matrix product per lag (l x n times n x l) spends most of its time packing operands.
  const MatrixXd channels = y.middleCols(t0, n + p + lags).transpose();
  MatrixXd r(l, l * lags);
  for (int k = 1; k <= lags; ++k)
    for (long a = 0; a < l; ++a)
      for (long c = 0; c < l; ++c)
        r(a, l * (k - 1) + c) =
            channels.col(a).segment(p + k, n).dot(channels.col(c).head(n)) / static_cast<double>(n);
  return r;
}

/// Block Hankel H = [R_1 .. R_i; R_2 .. R_{i+1}; ...; R_i .. R_{2i-1}] = O_i Gamma_i
/// (Peeters & De Roeck 1999; Van Overschee & De Moor 1996, Ch. 3), each R_k here R_{p+k}: then
/// Gamma_i = [A^p G, ..., A^{p+i-1} G] and O_i, hence A and the shapes C psi, are the same.
MatrixXd blockHankel(const MatrixXd& r, int i) {
  const long l = r.rows();
  MatrixXd h(i * l, i * l);
  for (int a = 0; a < i; ++a)
    for (int b = 0; b < i; ++b) h.block(a * l, b * l, l, l) = r.middleCols(l * (a + b), l);
  return h;
}

/// The subspace every model order shares: H = U S V^T, O = U_nmax S_nmax^{1/2}, and one QR of
/// O_up at the largest order (Doehler & Mevel 2012, "Fast multi-order computation of system
/// matrices": O_up,n = Q_n R_nn, so A_n = R_nn^{-1} (Q^T O_dw)[:n, :n]).
struct Subspace {
  MatrixXd u, v;
  VectorXd s;
  MatrixXd obs, rfull, qt_dw, qthin;
  long m = 0, rows_up = 0;
};

/// Throws InvalidInput naming the first non-finite sample.
void requireFiniteRecord(const Eigen::Ref<const Eigen::MatrixXd>& record) {
  if (record.allFinite()) return;  // the field is named only for the first bad sample
  for (long c = 0; c < record.cols(); ++c)
    for (long ch = 0; ch < record.rows(); ++ch)
      if (!std::isfinite(record(ch, c)))
        throwNotFinite("record(" + std::to_string(ch) + ", " + std::to_string(c) + ")",
                       record(ch, c));
}

/// The Hankel matrix as the mean of n_b blocks' (one block when nb = 0), with each block's lag
/// covariances for the variance (Doehler & Mevel 2013, Sections 3.2 and 5.1; Reynders et al.
/// 2008, the covariance of the Hankel matrix).
MatrixXd meanHankel(const MatrixXd& y, int i, int lags, int p, int nb, long usable, int l,
                    std::vector<MatrixXd>& block_r) {
  const long block = nb > 0 ? usable / nb : usable;
  MatrixXd r_mean = MatrixXd::Zero(l, l * lags);
  if (nb > 0) {
    block_r.reserve(nb);
    for (int b = 0; b < nb; ++b) {
      block_r.push_back(lagCovariances(y, b * block, block, lags, p));
      r_mean += block_r.back() / static_cast<double>(nb);
    }
  } else {
    r_mean = lagCovariances(y, 0, block, lags, p);
  }
  return blockHankel(r_mean, i);
}

/// H's SVD and the QR of O_up at nmax (Peeters & De Roeck 1999). Throws InvalidInput naming the
/// record's rms when H is zero.
Subspace decompose(const MatrixXd& h, const MatrixXd& y, int l, int nmax) {
  Subspace sub;
  sub.m = h.rows();
  Eigen::BDCSVD<MatrixXd> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  sub.u = svd.matrixU();
  sub.v = svd.matrixV();
  sub.s = svd.singularValues();
  if (!(sub.s[0] > 0.0))
    throwInvalid("record.rms", std::sqrt(y.squaredNorm() / y.size()),
                 "the record holds no correlated motion (a constant or empty record)");
  sub.obs = sub.u.leftCols(nmax) * sub.s.head(nmax).cwiseSqrt().asDiagonal();
  sub.rows_up = sub.m - l;
  Eigen::HouseholderQR<MatrixXd> qr(sub.obs.topRows(sub.rows_up));
  sub.rfull = qr.matrixQR().topRows(nmax).triangularView<Eigen::Upper>();
  sub.qt_dw = qr.householderQ().transpose() * sub.obs.bottomRows(sub.rows_up);
  sub.qthin = qr.householderQ() * MatrixXd::Identity(sub.rows_up, nmax);  // Q[:, :nmax]
  return sub;
}

/// Per block: the sensitivity coefficients of the left singular vectors outside the kept
/// subspace, C_b[k, j] = sqrt(s_j) (s_j a_kj + s_k a_jk) / (s_j^2 - s_k^2), a = U^T dH_b V, so
/// that the part of dO_n that changes the poles is U[:, n:] C_b[n:, :n] (first-order SVD
/// perturbation: Reynders et al. 2008, the sensitivity of the singular vectors; Doehler & Mevel
/// 2013 eqs. 28-34 in another normalisation). Perturbations inside span(U_n) are similarity
/// transforms of A_n and leave its eigenvalues unchanged, so the gap s_n - s_{n+1} is the only one
/// that enters.
std::vector<MatrixXd> singularVectorSensitivities(const std::vector<MatrixXd>& block_r,
                                                  const MatrixXd& h, const Subspace& sub, int i,
                                                  int nb, int nmax) {
  std::vector<MatrixXd> coeff;
  const double tscale = nb > 1 ? 1.0 / std::sqrt(static_cast<double>(nb) * (nb - 1)) : 0.0;
  if (nb <= 1) return coeff;
  const VectorXd& s = sub.s;
  coeff.reserve(nb);
  for (int b = 0; b < nb; ++b) {
    const MatrixXd dh = (blockHankel(block_r[b], i) - h) * tscale;
    const MatrixXd a = sub.u.transpose() * dh * sub.v;
    MatrixXd c = MatrixXd::Zero(sub.m, nmax);
    for (int j = 0; j < nmax; ++j)
      for (long k = j + 1; k < sub.m; ++k) {  // only k >= n > j is used
        const double den = s[j] * s[j] - s[k] * s[k];
        c(k, j) = std::sqrt(s[j]) * (s[j] * a(k, j) + s[k] * a(j, k)) / den;
      }
    coeff.push_back(std::move(c));
  }
  return coeff;
}

/// One order's state matrix and what its eigenvalues' sensitivities need.
struct OrderModel {
  int n = 0;
  MatrixXd rn, an, on, res;
  VectorXcd mu;
  MatrixXcd psi, psi_inv;
  std::vector<int> kept;  ///< eigenvalues with Im > 0: one per conjugate pair
};

/// d mu_j of the kept eigenvalues for each block (columns).
MatrixXcd eigenvalueSensitivities(const OrderModel& om, const Subspace& sub,
                                  const std::vector<MatrixXd>& coeff, int nb) {
  const int n = om.n;
  const auto rtri = om.rn.triangularView<Eigen::Upper>();
  MatrixXcd dmu(om.kept.size(), nb > 1 ? nb : 0);
  // The kept rows of Psi^{-1}, split into real and imaginary parts for real products with dA.
  MatrixXd inv_re(om.kept.size(), n), inv_im(om.kept.size(), n);
  for (size_t q = 0; q < om.kept.size(); ++q) {
    inv_re.row(q) = om.psi_inv.row(om.kept[q]).real();
    inv_im.row(q) = om.psi_inv.row(om.kept[q]).imag();
  }
  for (int b = 0; b < (nb > 1 ? nb : 0); ++b) {
    const MatrixXd dobs = sub.u.rightCols(sub.m - n) * coeff[b].bottomLeftCorner(sub.m - n, n);
    const auto dup = dobs.topRows(sub.rows_up);
    const auto ddw = dobs.bottomRows(sub.rows_up);
    // dA = O_up^+ (dO_dw - dO_up A) + (O_up^T O_up)^{-1} dO_up^T (O_dw - O_up A)
    // (the derivative of A = (O_up^T O_up)^{-1} O_up^T O_dw; Doehler & Mevel
    // 2013 eqs. 36-37), with O_up^T O_up = R^T R.
    // = R^{-1} (Q_n^T (dO_dw - dO_up A) + R^{-T} dO_up^T (O_dw - O_up A)).
    MatrixXd rhs = sub.qthin.leftCols(n).transpose() * (ddw - dup * om.an);
    rhs += rtri.transpose().solve(dup.transpose() * om.res);
    const MatrixXd da = rtri.solve(rhs);
    // d mu_j = chi_j^H dA psi_j / (chi_j^H psi_j) (Doehler & Mevel 2013 eq. 43).
    const MatrixXd w_re = inv_re * da, w_im = inv_im * da;
    for (size_t q = 0; q < om.kept.size(); ++q) {
      const int j = om.kept[q];
      std::complex<double> sum = 0.0;
      for (int k = 0; k < n; ++k)
        sum += std::complex<double>(w_re(q, k), w_im(q, k)) * om.psi(k, j);
      dmu(q, b) = sum;
    }
  }
  return dmu;
}

/// The pole of eigenvalue mu [-] of order n: lambda_c = ln(mu) / dt, its frequency, damping,
/// their std from the blocks' d mu (NaN with fewer than 2 blocks) and its shape C psi.
Pole poleOf(int n, std::complex<double> mu, const Eigen::Ref<const VectorXcd>& dmu, int nb,
            double dt, VectorXcd shape) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Pole p;
  p.order = n;
  const std::complex<double> lc = std::log(mu) / dt;  // lambda_c = ln(mu) / dt
  p.eigenvalue = lc;
  const double mag = std::abs(lc);
  p.frequency = mag / kTwoPi;
  p.damping = -lc.real() / mag;
  p.frequency_std = nan;
  p.damping_std = nan;
  if (nb > 1) {
    // f = |lc| / 2 pi, xi = -Re lc / |lc|, d lc = d mu / (mu dt)
    // (Doehler & Mevel 2013 Lemma 5).
    double vf = 0.0, vx = 0.0;
    for (int b = 0; b < nb; ++b) {
      const std::complex<double> dlc = dmu[b] / (mu * dt);
      const double dmag = (std::conj(lc) * dlc).real() / mag;
      const double df = dmag / kTwoPi;
      const double dx = -dlc.real() / mag + lc.real() * dmag / (mag * mag);
      vf += df * df;
      vx += dx * dx;
    }
    p.frequency_std = std::sqrt(vf);
    p.damping_std = std::sqrt(vx);
  }
  Eigen::Index big = 0;
  shape.cwiseAbs().maxCoeff(&big);
  if (std::abs(shape[big]) > 0.0) shape /= shape[big];
  p.shape = shape;
  return p;
}

/// Appends the poles of order n to `result` (none if the eigensolver fails).
void addPolesOfOrder(int n, const Subspace& sub, const std::vector<MatrixXd>& coeff, int l, int nb,
                     double dt, SsiResult& result) {
  OrderModel om;
  om.n = n;
  om.rn = sub.rfull.topLeftCorner(n, n);
  const auto rtri = om.rn.triangularView<Eigen::Upper>();
  om.an = rtri.solve(sub.qt_dw.topLeftCorner(n, n));
  om.on = sub.obs.leftCols(n);
  // Residual of the shift least squares O_up A = O_dw (enters dA).
  om.res = om.on.bottomRows(sub.rows_up) - om.on.topRows(sub.rows_up) * om.an;
  Eigen::EigenSolver<MatrixXd> eig(om.an);
  if (eig.info() != Eigen::Success) return;
  om.mu = eig.eigenvalues();
  om.psi = eig.eigenvectors();
  om.psi_inv = om.psi.partialPivLu().inverse();  // rows: chi_j^H / (chi_j^H psi_j)
  const MatrixXcd shapes = om.on.topRows(l).cast<std::complex<double>>() * om.psi;  // C psi
  for (int j = 0; j < n; ++j)
    if (om.mu[j].imag() > 0.0 && std::abs(om.mu[j]) > 0.0) om.kept.push_back(j);
  const MatrixXcd dmu = eigenvalueSensitivities(om, sub, coeff, nb);
  for (size_t q = 0; q < om.kept.size(); ++q) {
    const int j = om.kept[q];
    result.poles.push_back(poleOf(n, om.mu[j], dmu.row(q).transpose(), nb, dt, shapes.col(j)));
  }
}

}  // namespace

SsiCov::SsiCov(const SsiOptions& options) : options_(options) {
  if (options.min_order < 2 || options.min_order % 2 != 0)
    throwInvalid("ssi.min_order", options.min_order, "must be even and >= 2");
  if (options.max_order < options.min_order || options.max_order % 2 != 0)
    throwInvalid("ssi.max_order", options.max_order, "must be even and >= ssi.min_order");
  if (options.block_rows < 0) throwInvalid("ssi.block_rows", options.block_rows, "must be >= 0");
  if (options.variance_blocks < 0 || options.variance_blocks == 1)
    throwInvalid("ssi.variance_blocks", options.variance_blocks, "must be 0 or >= 2");
  if (options.skipped_lags < 0 || options.skipped_lags > 10000)
    throwInvalid("ssi.skipped_lags", options.skipped_lags, "must be from 0 to 10000");
}

int SsiCov::blockRows(int channels) const {
  if (options_.block_rows > 0) return options_.block_rows;
  // (i - 1) l >= max_order + l: one block row beyond the minimum, so that the shift least
  // squares stays overdetermined at the largest order.
  return (options_.max_order + channels + channels - 1) / channels + 1;
}

SsiResult SsiCov::identify(const Eigen::Ref<const Eigen::MatrixXd>& record,
                           double sample_rate) const {
  const int l = static_cast<int>(record.rows());
  if (l < 1) throwInvalid("record.channels", l, "must be >= 1");
  requirePositive("sample_rate", sample_rate);
  requireFiniteRecord(record);
  const int i = blockRows(l);
  if ((i - 1) * l < options_.max_order)
    throwInvalid("ssi.block_rows", i,
                 "(block_rows - 1) * channels (" + std::to_string(l) +
                     ") must be >= ssi.max_order " + std::to_string(options_.max_order));
  const int lags = 2 * i - 1;
  const int p = options_.skipped_lags;
  const int nb = options_.variance_blocks;
  const long usable = record.cols() - lags - p;  // t with t + p + 2i - 1 inside the record
  const long min_block = 4L * lags;
  if (usable < std::max(nb, 1) * min_block)
    throwInvalid("record.samples", static_cast<double>(record.cols()),
                 "too few for " + std::to_string(lags) + " lags in " +
                     std::to_string(std::max(nb, 1)) +
                     " blocks of >= " + std::to_string(min_block) + " samples");

  MatrixXd y = record;
  y.colwise() -= y.rowwise().mean();
  std::vector<MatrixXd> block_r;
  const MatrixXd h = meanHankel(y, i, lags, p, nb, usable, l, block_r);
  const int nmax = options_.max_order;
  const Subspace sub = decompose(h, y, l, nmax);
  const std::vector<MatrixXd> coeff = singularVectorSensitivities(block_r, h, sub, i, nb, nmax);

  SsiResult result;
  result.sample_rate = sample_rate;
  result.channels = l;
  result.block_rows = i;
  result.skipped_lags = p;
  result.min_order = options_.min_order;
  result.max_order = nmax;
  result.variance_blocks = nb > 1 ? nb : 0;
  const double dt = 1.0 / sample_rate;
  for (int n = options_.min_order; n <= nmax; n += 2)
    addPolesOfOrder(n, sub, coeff, l, nb, dt, result);
  return result;
}

}  // namespace drivetrain_stiffness::modal

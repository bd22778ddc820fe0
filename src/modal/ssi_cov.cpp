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

/// Lag covariances R_k = 1/N sum_t y_{t+k} y_t^T, k = 1..2i-1, over the columns t0..t0+n-1,
/// stacked as l x l blocks side by side (Peeters & De Roeck 1999, "covariance-driven SSI";
/// docs/vibration.md, "SSI-COV").
MatrixXd lagCovariances(const MatrixXd& y, long t0, long n, int lags) {
  const long l = y.rows();
  MatrixXd r(l, l * lags);
  for (int k = 1; k <= lags; ++k)
    r.middleCols(l * (k - 1), l).noalias() =
        y.middleCols(t0 + k, n) * y.middleCols(t0, n).transpose() / static_cast<double>(n);
  return r;
}

/// Block Hankel H = [R_1 .. R_i; R_2 .. R_{i+1}; ...; R_i .. R_{2i-1}] = O_i Gamma_i
/// (Peeters & De Roeck 1999; Van Overschee & De Moor 1996, Ch. 3).
MatrixXd blockHankel(const MatrixXd& r, int i) {
  const long l = r.rows();
  MatrixXd h(i * l, i * l);
  for (int a = 0; a < i; ++a)
    for (int b = 0; b < i; ++b) h.block(a * l, b * l, l, l) = r.middleCols(l * (a + b), l);
  return h;
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
  if (!record.allFinite())  // the field is named only for the first bad sample
    for (long c = 0; c < record.cols(); ++c)
      for (int ch = 0; ch < l; ++ch)
        if (!std::isfinite(record(ch, c)))
          throwNotFinite("record(" + std::to_string(ch) + ", " + std::to_string(c) + ")",
                         record(ch, c));
  const int i = blockRows(l);
  if ((i - 1) * l < options_.max_order)
    throwInvalid("ssi.block_rows", i,
                 "(block_rows - 1) * channels (" + std::to_string(l) +
                     ") must be >= ssi.max_order " + std::to_string(options_.max_order));
  const int lags = 2 * i - 1;
  const int nb = options_.variance_blocks;
  const long usable = record.cols() - lags;  // t with t + 2i - 1 inside the record
  const long min_block = 4L * lags;
  if (usable < std::max(nb, 1) * min_block)
    throwInvalid("record.samples", static_cast<double>(record.cols()),
                 "too few for " + std::to_string(lags) + " lags in " +
                     std::to_string(std::max(nb, 1)) +
                     " blocks of >= " + std::to_string(min_block) + " samples");

  MatrixXd y = record;
  y.colwise() -= y.rowwise().mean();

  // The Hankel matrix as the mean of the blocks' Hankel matrices, and the square root T of its
  // covariance, Sigma_H = T T^T, T_b = (h_b - mean h) / sqrt(n_b (n_b - 1)) (Doehler & Mevel 2013,
  // Sections 3.2 and 5.1; Reynders et al. 2008, the covariance of the Hankel matrix).
  const long block = nb > 0 ? usable / nb : usable;
  std::vector<MatrixXd> block_r;
  MatrixXd r_mean = MatrixXd::Zero(l, l * lags);
  if (nb > 0) {
    block_r.reserve(nb);
    for (int b = 0; b < nb; ++b) {
      block_r.push_back(lagCovariances(y, b * block, block, lags));
      r_mean += block_r.back() / static_cast<double>(nb);
    }
  } else {
    r_mean = lagCovariances(y, 0, block, lags);
  }
  const MatrixXd h = blockHankel(r_mean, i);
  const long m = h.rows();

  // H = U S V^T; O_n = U_n S_n^{1/2} (Peeters & De Roeck 1999).
  Eigen::BDCSVD<MatrixXd> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const MatrixXd& u = svd.matrixU();
  const MatrixXd& v = svd.matrixV();
  const VectorXd& s = svd.singularValues();
  if (!(s[0] > 0.0))
    throwInvalid("record.rms", std::sqrt(y.squaredNorm() / y.size()),
                 "the record holds no correlated motion (a constant or empty record)");
  const int nmax = options_.max_order;
  const MatrixXd obs = u.leftCols(nmax) * s.head(nmax).cwiseSqrt().asDiagonal();
  const long rows_up = m - l;
  // One QR of O_up at the largest order serves every order (Doehler & Mevel 2012, "Fast
  // multi-order computation of system matrices"): O_up,n = Q_n R_nn, so A_n = R_nn^{-1}
  // (Q^T O_dw)[:n, :n].
  Eigen::HouseholderQR<MatrixXd> qr(obs.topRows(rows_up));
  const MatrixXd rfull = qr.matrixQR().topRows(nmax).triangularView<Eigen::Upper>();
  const MatrixXd qt_dw = qr.householderQ().transpose() * obs.bottomRows(rows_up);
  const MatrixXd qthin = qr.householderQ() * MatrixXd::Identity(rows_up, nmax);  // Q[:, :nmax]

  // Per block: the sensitivity coefficients of the left singular vectors outside the kept
  // subspace, C_b[k, j] = sqrt(s_j) (s_j a_kj + s_k a_jk) / (s_j^2 - s_k^2), a = U^T dH_b V, so
  // that the part of dO_n that changes the poles is U[:, n:] C_b[n:, :n] (first-order SVD
  // perturbation: Reynders et al. 2008, the sensitivity of the singular vectors; Doehler & Mevel
  // 2013 eqs. 28-34 in another normalisation). Perturbations inside span(U_n) are similarity
  // transforms of A_n and leave its eigenvalues unchanged, so the gap s_n - s_{n+1} is the only one
  // that enters.
  std::vector<MatrixXd> coeff;
  const double tscale = nb > 1 ? 1.0 / std::sqrt(static_cast<double>(nb) * (nb - 1)) : 0.0;
  if (nb > 1) {
    coeff.reserve(nb);
    for (int b = 0; b < nb; ++b) {
      const MatrixXd dh = (blockHankel(block_r[b], i) - h) * tscale;
      const MatrixXd a = u.transpose() * dh * v;
      MatrixXd c = MatrixXd::Zero(m, nmax);
      for (int j = 0; j < nmax; ++j)
        for (long k = j + 1; k < m; ++k) {  // only k >= n > j is used
          const double den = s[j] * s[j] - s[k] * s[k];
          c(k, j) = std::sqrt(s[j]) * (s[j] * a(k, j) + s[k] * a(j, k)) / den;
        }
      coeff.push_back(std::move(c));
    }
  }

  SsiResult result;
  result.sample_rate = sample_rate;
  result.channels = l;
  result.block_rows = i;
  result.min_order = options_.min_order;
  result.max_order = nmax;
  result.variance_blocks = nb > 1 ? nb : 0;
  const double dt = 1.0 / sample_rate;
  const double nan = std::numeric_limits<double>::quiet_NaN();

  for (int n = options_.min_order; n <= nmax; n += 2) {
    const MatrixXd rn = rfull.topLeftCorner(n, n);
    const auto rtri = rn.triangularView<Eigen::Upper>();
    const MatrixXd an = rtri.solve(qt_dw.topLeftCorner(n, n));
    const MatrixXd on = obs.leftCols(n);
    // Residual of the shift least squares O_up A = O_dw (enters dA below).
    const MatrixXd res = on.bottomRows(rows_up) - on.topRows(rows_up) * an;
    Eigen::EigenSolver<MatrixXd> eig(an);
    if (eig.info() != Eigen::Success) continue;
    const VectorXcd mu = eig.eigenvalues();
    const MatrixXcd psi = eig.eigenvectors();
    const MatrixXcd psi_inv = psi.partialPivLu().inverse();  // rows: chi_j^H / (chi_j^H psi_j)
    const MatrixXcd shapes = on.topRows(l).cast<std::complex<double>>() * psi;  // C psi

    // d lambda_j for each block (columns), only for the kept poles.
    std::vector<int> kept;
    for (int j = 0; j < n; ++j)
      if (mu[j].imag() > 0.0 && std::abs(mu[j]) > 0.0) kept.push_back(j);
    MatrixXcd dmu(kept.size(), nb > 1 ? nb : 0);
    // The kept rows of Psi^{-1}, split into real and imaginary parts for real products with dA.
    MatrixXd inv_re(kept.size(), n), inv_im(kept.size(), n);
    for (size_t q = 0; q < kept.size(); ++q) {
      inv_re.row(q) = psi_inv.row(kept[q]).real();
      inv_im.row(q) = psi_inv.row(kept[q]).imag();
    }
    for (int b = 0; b < (nb > 1 ? nb : 0); ++b) {
      const MatrixXd dobs = u.rightCols(m - n) * coeff[b].bottomLeftCorner(m - n, n);
      const auto dup = dobs.topRows(rows_up);
      const auto ddw = dobs.bottomRows(rows_up);
      // dA = O_up^+ (dO_dw - dO_up A) + (O_up^T O_up)^{-1} dO_up^T (O_dw - O_up A)
      // (the derivative of A = (O_up^T O_up)^{-1} O_up^T O_dw; Doehler & Mevel
      // 2013 eqs. 36-37), with O_up^T O_up = R^T R.
      // = R^{-1} (Q_n^T (dO_dw - dO_up A) + R^{-T} dO_up^T (O_dw - O_up A)).
      MatrixXd rhs = qthin.leftCols(n).transpose() * (ddw - dup * an);
      rhs += rtri.transpose().solve(dup.transpose() * res);
      const MatrixXd da = rtri.solve(rhs);
      // d mu_j = chi_j^H dA psi_j / (chi_j^H psi_j) (Doehler & Mevel 2013 eq. 43).
      const MatrixXd w_re = inv_re * da, w_im = inv_im * da;
      for (size_t q = 0; q < kept.size(); ++q) {
        const int j = kept[q];
        std::complex<double> sum = 0.0;
        for (int k = 0; k < n; ++k) sum += std::complex<double>(w_re(q, k), w_im(q, k)) * psi(k, j);
        dmu(q, b) = sum;
      }
    }
    for (size_t q = 0; q < kept.size(); ++q) {
      const int j = kept[q];
      Pole p;
      p.order = n;
      const std::complex<double> lc = std::log(mu[j]) / dt;  // lambda_c = ln(mu) / dt
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
          const std::complex<double> dlc = dmu(q, b) / (mu[j] * dt);
          const double dmag = (std::conj(lc) * dlc).real() / mag;
          const double df = dmag / kTwoPi;
          const double dx = -dlc.real() / mag + lc.real() * dmag / (mag * mag);
          vf += df * df;
          vx += dx * dx;
        }
        p.frequency_std = std::sqrt(vf);
        p.damping_std = std::sqrt(vx);
      }
      VectorXcd shape = shapes.col(j);
      Eigen::Index big = 0;
      shape.cwiseAbs().maxCoeff(&big);
      if (std::abs(shape[big]) > 0.0) shape /= shape[big];
      p.shape = shape;
      result.poles.push_back(std::move(p));
    }
  }
  return result;
}

}  // namespace drivetrain_stiffness::modal

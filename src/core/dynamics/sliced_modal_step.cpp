#include "drivetrain_stiffness/core/dynamics/sliced_modal_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace drivetrain_stiffness {
namespace sliced {
namespace {

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

}  // namespace

void prepare(const ContactRules& rules, const Slice& s, MeshRegime r, int j, const State6& y,
             Complex e_theta0, double w, double drive_force, Piece& out) {
  const double te_amplitude = rules.teAmplitude();
  const MeshTerms& t = rules.conditions(r, j).terms;  // tabulated: this runs at every step
  // Forcing in modal coordinates: U sin(theta) + W w cos(theta) + G, written as
  // P e^{i w s} + Q e^{-i w s} + G with sin x = (e^{ix} - e^{-ix}) / 2i, cos x = (e^{ix} + e^{-ix})
  // / 2.
  const double u = -t.stiffness * te_amplitude, wc = -t.damping * te_amplitude * w;
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

void advance(const Slice& s, const Piece& piece, double w, double h, Complex e_mu, State6& y) {
  // eta(h) = e^{lambda h} R + P' e^{iwh} + Q' e^{-iwh} + G' (the particular form, no division), or
  // where some |mu - lambda| h < 0.05 the same by the forced integrals E with their phi_1 series
  // (the particular form would lose eps / |z| to cancellation there, as the quotient would).
  const Complex mu(0.0, w), e_mu_conj = std::conj(e_mu);
  State6 next = State6::Zero();
  for (int i = 0; i < piece.n; ++i) {
    const int k = piece.k[i];
    const Complex lambda = s.lambda[k];
    // e^{lambda h} as glibc's cexp computes it for Re(lambda h) <= 709 (here: a passive mode has
    // Re lambda <= 0): exp of the real part times the sine and cosine of the imaginary part, one
    // sincos, without cexp's classification of the argument; cexp's results to the bit (a review
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

double regimeMargin(const ContactRules& rules, const Slice& s, MeshRegime r, int j,
                    const Piece& piece, Complex e_theta0, double w) {
  const double te_amplitude = rules.teAmplitude();
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
  delta_sin += Complex(0.0, te_amplitude) * e_theta0;
  rate_sin += -te_amplitude * w * e_theta0;
  spread_d += l1(delta_sin);
  spread_r += l1(rate_sin);
  const RegimeConditions& rc = rules.conditions(r, j);
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

}  // namespace sliced
}  // namespace drivetrain_stiffness

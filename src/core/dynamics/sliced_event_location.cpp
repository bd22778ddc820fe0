#include "drivetrain_stiffness/core/dynamics/sliced_event_location.hpp"

#include <algorithm>
#include <cmath>

namespace drivetrain_stiffness {
namespace sliced {

double locateChange(const ContactRules& rules, const Slice& s, const Piece& piece, MeshRegime r,
                    int j, Complex e_theta, double w, double h, const State6& start,
                    const State6& end, Complex* e_hi) {
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
  double g_lo = std::max(rules.regimeValue(r, j, start, e_theta, w), 0.0);
  double g_hi = std::min(rules.regimeValue(r, j, end, *e_hi, w), 0.0);
  State6 z;
  for (int i = 1; i < kEventSamples; ++i) {
    const double t = h * i / kEventSamples;
    const Complex e_mu = std::polar(1.0, w * t);
    advance(s, piece, w, t, e_mu, z);
    const Complex e_t = e_theta * e_mu;
    const double g = rules.regimeValue(r, j, z, e_t, w);
    if (!rules.inRegime(r, j, z, e_t, w)) {
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
    const double g = rules.regimeValue(r, j, z, e_t, w);
    if (rules.inRegime(r, j, z, e_t, w)) {
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

}  // namespace sliced
}  // namespace drivetrain_stiffness

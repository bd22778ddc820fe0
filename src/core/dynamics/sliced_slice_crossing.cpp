#include "drivetrain_stiffness/core/dynamics/sliced_slice_crossing.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {
namespace sliced {

double SliceCrossing::propagateLinear(const ContactRules& rules, const SliceTables& tables,
                                      State6& y, double& phase, double f, double duration,
                                      double drive_force) const {
  if (!(duration >= 0.0) || !std::isfinite(f) || !std::isfinite(phase) ||
      !std::isfinite(drive_force))
    return 0.0;
  Walk k;
  k.rules = &rules;
  k.tables = &tables;
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

bool SliceCrossing::takeRegime(Walk& k, double w) const {
  const std::optional<MeshRegime> found = k.rules->regimeAt(k.j, k.z, k.e_theta, w);
  if (found) k.regime = *found;
  return found.has_value();
}

double SliceCrossing::stepLength(const Walk& k, double f, double& next, bool& crossing) const {
  const SlicedMesh& m = k.rules->slices();
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

bool SliceCrossing::walkStep(Walk& k, double f, double drive_force) const {
  const SlicedMesh& m = k.rules->slices();
  const double w = kTwoPi * f;
  if (f < 0.0 && k.frac == 0.0) {  // backwards from a period boundary: the top of the period below
    k.whole -= 1.0;
    k.frac = 1.0;
  }
  if (k.j < 0) {  // the contacts the call starts with
    k.j = m.sliceAt(k.frac == 1.0 ? std::nextafter(1.0, 0.0) : k.frac, f < 0.0);
    if (!takeRegime(k, w)) return false;
  }
  const Slice& s = k.tables->slice(k.regime, k.j, *k.rules);
  if (!s.usable) return false;
  double next;
  bool crossing;
  double h = stepLength(k, f, next, crossing);
  // The contacts must keep their state through the step, not only at its ends: where the bound
  // cannot show it, the step is cut to an eighth of the fastest mode's period, so that the checks
  // at the ends sample every oscillation that could lift a flank (a change missed between two of
  // them would be one that stays open for less than that).
  Piece& piece = piece_;
  prepare(*k.rules, s, k.regime, k.j, k.z, k.e_theta, w, drive_force, piece);
  if (regimeMargin(*k.rules, s, k.regime, k.j, piece, k.e_theta, w) <= 0.0) {
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
  const bool leaves = !k.rules->inRegime(k.regime, k.j, k.z_end, e_end, w);
  if (leaves) {
    // A contact changed inside the step: located on this regime's exact solution, the state
    // just past the change goes on in the regime it is in there.
    if (++k.changes > kMaxChangesPerCall) return false;  // chatter: dopri5's to resolve
    Complex e_hi = e_end;
    const double hi =
        locateChange(*k.rules, s, piece, k.regime, k.j, k.e_theta, w, h, k.z, k.z_end, &e_hi);
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

bool SliceCrossing::endStep(Walk& k, double f, double h, double next, bool crossing, bool leaves,
                            Complex e_end) const {
  const int n = k.rules->slices().size();
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
  if ((leaves || crossing) && !k.rules->inRegime(k.regime, k.j, k.z, k.e_theta, w)) {
    if (!takeRegime(k, w)) return false;
    ++events_;
  }
  return true;
}

}  // namespace sliced
}  // namespace drivetrain_stiffness

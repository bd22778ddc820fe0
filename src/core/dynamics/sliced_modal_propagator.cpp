#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"

#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/turns.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

using sliced::Complex;
using sliced::CVector;
using sliced::FlankLaw;
using sliced::FlankState;
using sliced::MeshRegime;
using sliced::Slice;

SlicedModalPropagator::SlicedModalPropagator(const GearRotorParameters& p,
                                             std::shared_ptr<const SlicedMesh> slices,
                                             double te_amplitude, double backlash)
    : rules_(std::move(slices), te_amplitude, backlash) {
  // The three usual regimes' rules are tabulated (ContactRules), the others when first met. The
  // slices of each regime are sized when a parameter set first uses them.
  setParameters(p);
  for (MeshRegime r : {MeshRegime::kBothFlanks, MeshRegime::kDriveFlank, MeshRegime::kBackFlank}) {
    tables_.sizeRegime(r, rules_.slices().size());
  }
}

void SlicedModalPropagator::setParameters(const GearRotorParameters& p) {
  p.validate();
  if (p.bearing_clearance[0] > 0.0 || p.bearing_clearance[1] > 0.0) {
    throw InvalidInput(
        "exact propagation: bearing clearance makes the model nonlinear at every crossing; use "
        "dopri5");
  }
  const double m_s = p.equivalentMass();
  tables_.select(p, m_s);
  rules_.setMeshDamping(p.mesh_damping);
  // trace(M^-1 K) = (k_b1 + k) / m_p + (k_b2 + k) / m_g + k / m_s at the stiffest mesh k of any
  // regime (both flanks: k1 + k_c), which bounds every omega^2 of the undamped problem.
  double k = 0.0;
  for (int j = 0; j < rules_.slices().size(); ++j)
    k = std::max(k, rules_.slices().k1(j) + rules_.slices().kChain(j));
  const double trace = (p.bearing_stiffness[0] + k) / p.pinion_mass +
                       (p.bearing_stiffness[1] + k) / p.gear_mass + k / m_s;
  fastest_period_bound_ =
      trace > 0.0 ? kTwoPi / std::sqrt(trace) : std::numeric_limits<double>::infinity();
}

double SlicedModalPropagator::propagateLinear(State6& y, double& phase, double f, double duration,
                                              double drive_force) const {
  return crossing_.propagateLinear(rules_, tables_, y, phase, f, duration, drive_force);
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

Matrix6 SlicedModalPropagator::monodromy(double f) const {
  return monodromyIn(rules_.loadedRegime(), f);
}

bool SlicedModalPropagator::loadedSliceMap(int j, double phase, double f, double h,
                                           AffineMap& out) const {
  const MeshRegime r = rules_.loadedRegime();
  const Slice& s = tables_.slice(r, j, rules_);
  if (!s.usable) return false;
  const double w = kTwoPi * f;
  const Complex e_theta = std::polar(1.0, kTwoPi * phase), e_mu = std::polar(1.0, w * h);
  // The forced part from rest without drive force, and the unit drive force's part as the same
  // with F_d = 1 less that: the solution propagateLinear advances a state by (prepare, advance).
  const State6 rest = State6::Zero();
  sliced::prepare(rules_, s, r, j, rest, e_theta, w, 0.0, piece_);
  sliced::advance(s, piece_, w, h, e_mu, out.forced);
  sliced::prepare(rules_, s, r, j, rest, e_theta, w, 1.0, piece_);
  sliced::advance(s, piece_, w, h, e_mu, out.drive);
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
    const Slice& s = tables_.slice(rules_.loadedRegime(),
                                   rules_.slices().sliceAt((i + 0.5) / 16.0, false), rules_);
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
  const int j = rules_.slices().sliceAt(frac, f < 0.0);
  return rules_.inRegime(rules_.loadedRegime(), j, y, std::polar(1.0, kTwoPi * frac), kTwoPi * f);
}

std::optional<Matrix6> SlicedModalPropagator::monodromy(double f, const State6& y,
                                                        double phase) const {
  requireFinite("mesh frequency", f);
  requireFinite("mesh phase", phase);
  const double te_amplitude = rules_.teAmplitude();
  // wrapTurns, as inLoadedRegime: phase - floor(phase) rounds to 1.0 for a phase just below an
  // integer (-1e-17), which sliceAt would clamp to the last slice where the period's first is
  // meant.
  const double frac = wrapTurns(phase);
  const int j = rules_.slices().sliceAt(frac, f < 0.0);
  const Complex e_theta = std::polar(1.0, kTwoPi * frac);
  const std::optional<MeshRegime> r = rules_.regimeAt(j, y, e_theta, kTwoPi * f);
  if (!r) return std::nullopt;
  // A period-long map describes the motion only in the regimes a flank holds for a period: both
  // loaded, or one loaded and the other open. A stiffened flank (just landed) or a damper clipped
  // at zero (opening) is a moment, as is any state that the period map of its regime would
  // misdescribe: no margin there.
  if (*r != MeshRegime::kBothFlanks && *r != MeshRegime::kDriveFlank &&
      *r != MeshRegime::kBackFlank)
    return std::nullopt;
  const double delta = y[2] + y[0] - y[1] - te_amplitude * e_theta.imag();
  for (int flank = 0; flank < 2; ++flank) {
    const FlankState state = flank == 0 ? sliced::driveState(*r) : sliced::backState(*r);
    const FlankLaw law = rules_.flankLaw(flank, j);
    if (state == FlankState::kUnloaded && law.exists && law.c0 + law.alpha * delta > 0.0)
      return std::nullopt;
  }
  return monodromyIn(*r, f);
}

Matrix6 SlicedModalPropagator::monodromyIn(MeshRegime r, double f) const {
  requireFinite("mesh frequency", f);
  if (f == 0.0) throw InvalidInput("monodromy: the mesh must turn (mesh frequency 0)");
  Matrix6 phi = Matrix6::Identity();
  const int n = rules_.slices().size();
  for (int i = 0; i < n; ++i) {
    const int j = f > 0.0 ? i : n - 1 - i;
    const Slice& s = tables_.slice(r, j, rules_);
    const double tau = (rules_.slices().end(j) - rules_.slices().start(j)) / std::abs(f);
    CVector e;
    for (int k = 0; k < 6; ++k) e[k] = std::exp(s.lambda[k] * tau);
    phi = (s.v * e.asDiagonal() * s.v_inv).real() * phi;
  }
  return phi;
}

}  // namespace drivetrain_stiffness

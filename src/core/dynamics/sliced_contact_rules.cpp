#include "drivetrain_stiffness/core/dynamics/sliced_contact_rules.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace sliced {

ContactRules::ContactRules(std::shared_ptr<const SlicedMesh> slices, double te_amplitude,
                           double backlash)
    : slices_(std::move(slices)), te_amplitude_(te_amplitude), backlash_(backlash) {
  if (!slices_) throw InvalidInput("sliced propagator: no sliced mesh");
  requireNonNegative("transmission_error_amplitude", te_amplitude);
  requireNonNegative("backlash", backlash);
  // The three usual regimes' rules now; the others (stiffened flanks, both unloaded) when first
  // met.
  for (MeshRegime r : {MeshRegime::kBothFlanks, MeshRegime::kDriveFlank, MeshRegime::kBackFlank}) {
    conditions_[static_cast<std::size_t>(r)].resize(static_cast<std::size_t>(slices_->size()));
  }
}

void ContactRules::setMeshDamping(double c) {
  mesh_damping_ = c;
  // The contact rules depend on the mesh damping (flankLaw, meshTerms; the slices, the preload
  // force, the backlash and the TE amplitude are the rules' own): tabulated here, read at
  // every step, no allocation (the tables keep their size). Remade only when that damping changed:
  // a bearing-stiffness change, which under a rippling load above the anti-backlash knee comes
  // hundreds of times a second, keeps them (all regimes' tables took 13 % of such a replay).
  if (!(c == conditions_mesh_damping_)) {
    for (int r = 0; r < kRegimes; ++r) {
      std::vector<RegimeConditions>& table = conditions_[static_cast<std::size_t>(r)];
      for (std::size_t j = 0; j < table.size(); ++j)
        table[j] = makeConditions(static_cast<MeshRegime>(r), static_cast<int>(j));
    }
    conditions_mesh_damping_ = c;
  }
}

void ContactRules::tabulateRegimeConditions(MeshRegime r) const {
  // Once per regime and propagator (not in the steady state of a run): sized, its rules tabulated
  // for the mesh damping of now (setMeshDamping keeps every allocated table up to date).
  const std::size_t n = static_cast<std::size_t>(slices_->size());
  std::vector<RegimeConditions>& table = conditions_[static_cast<std::size_t>(r)];
  table.resize(n);
  for (std::size_t j = 0; j < n; ++j) table[j] = makeConditions(r, static_cast<int>(j));
}

FlankLaw ContactRules::flankLaw(int flank, int j) const {
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
    return {fp, -kc, -(mesh_damping_ - c1), kc > 0.0};
  }
  const double sign = flank == 0 ? 1.0 : -1.0;
  return {-k1 * backlash_, sign * k1, sign * mesh_damping_, k1 > 0.0};
}

MeshTerms ContactRules::meshTerms(MeshRegime r, int j) const {
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

double ContactRules::driveFlankDamping(int j) const {
  // The mesh damping shared as the stiffness is (GearRotorModel::forces): c1 = c k1 / (k1 + k_c).
  const double k1 = slices_->k1(j), kc = slices_->kChain(j);
  return k1 + kc > 0.0 ? mesh_damping_ * k1 / (k1 + kc) : 0.0;
}

RegimeConditions ContactRules::makeConditions(MeshRegime r, int j) const {
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

double ContactRules::regimeValue(MeshRegime r, int j, const State6& y, Complex e_theta,
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

bool ContactRules::inRegime(MeshRegime r, int j, const State6& y, Complex e_theta, double w) const {
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

std::optional<MeshRegime> ContactRules::regimeAt(int j, const State6& y, Complex e_theta,
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

}  // namespace sliced
}  // namespace drivetrain_stiffness

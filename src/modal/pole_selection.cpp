#include "drivetrain_stiffness/modal/pole_selection.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness::modal {

const char* poleStatusName(PoleStatus s) {
  switch (s) {
    case PoleStatus::kOrderBand: return "order band";
    case PoleStatus::kInadmissible: return "inadmissible";
    case PoleStatus::kUnstable: return "unstable";
    case PoleStatus::kStable: return "stable";
    case PoleStatus::kSelected: return "selected";
  }
  return "unknown";
}

double mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  if (a.size() != b.size())
    throwInvalid("mac.shape_size", static_cast<double>(b.size()),
                 "must equal the other shape's size " + std::to_string(a.size()));
  const double na = a.squaredNorm(), nb = b.squaredNorm();
  if (!(na > 0.0 && nb > 0.0)) return 0.0;
  // Allemang & Brown 1982: MAC = |a^H b|^2 / ((a^H a)(b^H b)).
  return std::norm(a.dot(b)) / (na * nb);
}

namespace {

void validate(const SelectionOptions& o) {
  requireInOpenRange("selection.stable_frequency", o.stable_frequency, 0.0, 1.0);
  requirePositive("selection.stable_damping", o.stable_damping);
  requireInClosedRange("selection.stable_mac", o.stable_mac, 0.0, 1.0);
  requireInOpenRange("selection.max_damping", o.max_damping, 0.0, 1.0);
  requireInOpenRange("selection.cluster_frequency", o.cluster_frequency, 0.0, 1.0);
  requireInClosedRange("selection.cluster_mac", o.cluster_mac, 0.0, 1.0);
  requireInClosedRange("selection.min_orders_fraction", o.min_orders_fraction, 0.0, 1.0);
  requireNonNegative("selection.damping_significance", o.damping_significance);
  requirePositive("selection.frequency_resolution", o.frequency_resolution);
  requireNonNegative("selection.resolution_sigmas", o.resolution_sigmas);
  requireNonNegative("selection.line_damping", o.line_damping);
}

/// Whether `p` lies in a band that sets it aside: any band, or a lines_only one when p is
/// line-like (an order's residual line has no damping; a mode seen through the order has).
bool setAside(const Pole& p, const std::vector<FrequencyBand>& bands, const SelectionOptions& o) {
  const bool line =
      !(p.damping >= o.line_damping) ||
      (std::isfinite(p.damping_std) && !(p.damping > o.damping_significance * p.damping_std));
  return std::any_of(bands.begin(), bands.end(), [&](const FrequencyBand& b) {
    return p.frequency >= b.low && p.frequency <= b.high && (!b.lines_only || line);
  });
}

using PolesByOrder = std::map<int, std::vector<const Pole*>>;
using Cluster = std::vector<const Pole*>;

/// The hard criteria: poles in an excluded band to `order_poles`, damping outside
/// (0, max_damping) dropped, the rest by order.
PolesByOrder admissiblePoles(const SsiResult& ssi, const std::vector<FrequencyBand>& excluded,
                             const SelectionOptions& o, std::vector<Pole>& order_poles) {
  PolesByOrder by_order;
  for (const Pole& p : ssi.poles) {
    if (setAside(p, excluded, o)) {
      order_poles.push_back(p);
      continue;
    }
    if (!(p.damping > 0.0 && p.damping < o.max_damping)) continue;
    by_order[p.order].push_back(&p);
  }
  return by_order;
}

/// Stabilisation: a pole is stable when the order below or above holds one of close frequency,
/// damping and shape (Peeters & De Roeck 2001, the stabilisation diagram; Reynders et al. 2012).
/// The stable poles by increasing frequency.
std::vector<const Pole*> stablePoles(const PolesByOrder& by_order, const SelectionOptions& o) {
  auto matches = [&](const Pole* p, int order) {
    const auto other = by_order.find(order);
    if (other == by_order.end()) return false;
    return std::any_of(other->second.begin(), other->second.end(), [&](const Pole* q) {
      return std::abs(p->frequency - q->frequency) < o.stable_frequency * p->frequency &&
             std::abs(p->damping - q->damping) < o.stable_damping * p->damping &&
             mac(p->shape, q->shape) >= o.stable_mac;
    });
  };
  std::vector<const Pole*> stable;
  for (const auto& [n, poles] : by_order)
    for (const Pole* p : poles)
      if (matches(p, n - 2) || matches(p, n + 2)) stable.push_back(p);
  std::sort(stable.begin(), stable.end(),
            [](const Pole* a, const Pole* b) { return a->frequency < b->frequency; });
  return stable;
}

/// Clustering: each stable pole, by increasing frequency, joins the cluster whose first pole is
/// within cluster_frequency and cluster_mac, else opens one.
std::vector<Cluster> clusterPoles(const std::vector<const Pole*>& stable,
                                  const SelectionOptions& o) {
  std::vector<Cluster> clusters;
  for (const Pole* p : stable) {
    Cluster* home = nullptr;
    for (auto& c : clusters) {
      const Pole* first = c.front();
      if (std::abs(p->frequency - first->frequency) < o.cluster_frequency * first->frequency &&
          mac(p->shape, first->shape) >= o.cluster_mac) {
        home = &c;
        break;
      }
    }
    if (home)
      home->push_back(p);
    else
      clusters.push_back({p});
  }
  return clusters;
}

/// The cluster's mode, or nullopt for a spurious cluster: poles from fewer than `needed` orders,
/// or (with std) none whose damping is significant.
std::optional<IdentifiedMode> modeOf(const Cluster& c, const SsiResult& ssi,
                                     const SelectionOptions& o, int needed) {
  // A pole is resolved when its frequency is known within half its resonance's half-width (see
  // frequency_resolution); above the true order the record's noise adds poles beside a mode that
  // are not, and only two resolved poles of one order make it doubled.
  const bool with_std = ssi.variance_blocks > 0;
  auto resolved = [&](const Pole* p) {
    return !with_std || p->frequency_std <= o.frequency_resolution * p->damping * p->frequency;
  };
  std::set<int> orders, resolved_orders;
  int doubled = 0;  // orders that put two resolved poles into the cluster
  for (const Pole* p : c) {
    orders.insert(p->order);
    if (resolved(p)) doubled += resolved_orders.insert(p->order).second ? 0 : 1;
  }
  if (static_cast<int>(orders.size()) < needed) return std::nullopt;
  // Unresolved when an order sees two resolved poles here, or when fewer than half the resolved
  // members agree with their median within 2 of their std (below): close modes of one shape,
  // whose poles wander between them from order to order.
  bool unresolved = doubled > 0;
  // The representative: among the resolved members within 2 std of their median frequency (the
  // orders where the pole has converged), the one with the smallest frequency std, the order at
  // which the first-order propagation's singular-value gap is clearest (docs/vibration.md,
  // "Variance propagation"). Too low an order biases its pole, with a small std: on 50 simulated
  // rigs the smallest-std member over the whole cluster erred by -0.085 % on average, 3 of its
  // std. Unresolved members (noise beside the mode) would drag the median. Without std, the
  // member of median frequency.
  std::vector<const Pole*> by_frequency;
  for (const Pole* p : c)
    if (resolved(p)) by_frequency.push_back(p);
  if (by_frequency.empty()) return std::nullopt;  // no member resolved: noise
  std::sort(by_frequency.begin(), by_frequency.end(),
            [](const Pole* a, const Pole* b) { return a->frequency < b->frequency; });
  const Pole* rep = by_frequency[by_frequency.size() / 2];
  const double median = rep->frequency;
  if (with_std) {
    std::size_t agree = 0;
    for (const Pole* p : by_frequency) {
      const bool converged = std::abs(p->frequency - median) <= 2.0 * p->frequency_std;
      agree += converged ? 1 : 0;
      if (converged && p->frequency_std < rep->frequency_std) rep = p;
    }
    unresolved = unresolved || 2 * agree < by_frequency.size();
  }
  const bool significant = std::any_of(c.begin(), c.end(), [&](const Pole* p) {
    return p->damping > o.damping_significance * p->damping_std;
  });
  if (with_std && !significant) return std::nullopt;
  IdentifiedMode m;
  m.frequency = rep->frequency;
  m.frequency_std = rep->frequency_std;
  m.damping = rep->damping;
  m.damping_std = rep->damping_std;
  m.shape = rep->shape;
  m.order = rep->order;
  m.orders = static_cast<int>(orders.size());
  m.frequency_spread = c.back()->frequency - c.front()->frequency;
  m.unresolved = unresolved;
  return m;
}

/// Neighbours closer than resolution_sigmas std of their difference are not resolved.
void markUnresolved(std::vector<IdentifiedMode>& modes, const SelectionOptions& o) {
  for (size_t k = 1; k < modes.size(); ++k) {
    IdentifiedMode &a = modes[k - 1], &b = modes[k];
    const double sd = std::hypot(a.frequency_std, b.frequency_std);
    if (b.frequency - a.frequency < o.resolution_sigmas * sd) a.unresolved = b.unresolved = true;
  }
}

/// SelectionResult::status and mode_of from the selection's intermediate results; `reported[j]`
/// became mode `j` before the sort by frequency put it at the position where by_frequency holds j.
void noteStatus(const SsiResult& ssi, const std::vector<FrequencyBand>& excluded,
                const SelectionOptions& o, const std::vector<const Pole*>& stable,
                const std::vector<const Cluster*>& reported,
                const std::vector<std::size_t>& by_frequency, SelectionResult& out) {
  const std::size_t n = ssi.poles.size();
  out.status.assign(n, PoleStatus::kUnstable);
  out.mode_of.assign(n, -1);
  auto index = [&](const Pole* p) { return static_cast<std::size_t>(p - ssi.poles.data()); };
  for (std::size_t i = 0; i < n; ++i) {
    const Pole& p = ssi.poles[i];
    if (setAside(p, excluded, o))
      out.status[i] = PoleStatus::kOrderBand;
    else if (!(p.damping > 0.0 && p.damping < o.max_damping))
      out.status[i] = PoleStatus::kInadmissible;
  }
  for (const Pole* p : stable) out.status[index(p)] = PoleStatus::kStable;
  for (std::size_t k = 0; k < by_frequency.size(); ++k) {
    for (const Pole* p : *reported[by_frequency[k]]) {
      out.status[index(p)] = PoleStatus::kSelected;
      out.mode_of[index(p)] = static_cast<int>(k);
    }
  }
}

}  // namespace

SelectionResult selectModes(const SsiResult& ssi, const std::vector<FrequencyBand>& excluded,
                            const SelectionOptions& o) {
  validate(o);
  for (size_t k = 0; k < excluded.size(); ++k) {
    requireFinite("excluded[" + std::to_string(k) + "].low", excluded[k].low);
    requireFinite("excluded[" + std::to_string(k) + "].high", excluded[k].high);
  }
  SelectionResult out;
  const PolesByOrder by_order = admissiblePoles(ssi, excluded, o, out.order_poles);
  const std::vector<const Pole*> stable = stablePoles(by_order, o);
  const std::vector<Cluster> clusters = clusterPoles(stable, o);
  const int n_orders = (ssi.max_order - ssi.min_order) / 2 + 1;
  const int needed = std::max(3, static_cast<int>(std::ceil(o.min_orders_fraction * n_orders)));
  std::vector<const Cluster*> reported;
  for (const Cluster& c : clusters) {
    if (std::optional<IdentifiedMode> m = modeOf(c, ssi, o, needed)) {
      out.modes.push_back(std::move(*m));
      reported.push_back(&c);
    } else {
      ++out.spurious_clusters;
    }
  }
  std::vector<std::size_t> by_frequency(out.modes.size());
  for (std::size_t k = 0; k < by_frequency.size(); ++k) by_frequency[k] = k;
  std::stable_sort(by_frequency.begin(), by_frequency.end(), [&](std::size_t a, std::size_t b) {
    return out.modes[a].frequency < out.modes[b].frequency;
  });
  std::vector<IdentifiedMode> sorted;
  for (std::size_t k : by_frequency) sorted.push_back(std::move(out.modes[k]));
  out.modes = std::move(sorted);
  markUnresolved(out.modes, o);
  noteStatus(ssi, excluded, o, stable, reported, by_frequency, out);
  return out;
}

}  // namespace drivetrain_stiffness::modal

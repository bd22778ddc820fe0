// Automatic pole selection from SsiCov's poles of every order: stabilisation across orders,
// clustering of the stable poles, one representative per cluster. No user picking. Criteria and
// their reasons: docs/vibration.md, "Pole selection".
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/modal/ssi_cov.hpp"

namespace drivetrain_stiffness::modal {

/// Modal assurance criterion |a^H b|^2 / (|a|^2 |b|^2) in [0, 1]; 0 when either is zero. Throws
/// InvalidInput when the sizes differ.
double mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b);

/// A frequency band [low, high] [Hz] with what it holds (a removed order).
struct FrequencyBand {
  double low = 0.0, high = 0.0;
  std::string label;
  /// Only line-like poles inside are set aside (damping below line_damping or not significant):
  /// a removed order's band, through which a damped mode still shows. False: every pole inside.
  bool lines_only = false;
};

/// Thresholds of the selection (docs/vibration.md, "Pole selection").
struct SelectionOptions {
  double stable_frequency = 0.01;    ///< |f_n - f_{n+-2}| / f_n below this [-]
  double stable_damping = 0.5;       ///< |xi_n - xi_{n+-2}| / xi_n below this [-]
  double stable_mac = 0.95;          ///< MAC(shape_n, shape_{n+-2}) at least this [-]
  double max_damping = 0.2;          ///< damping ratios outside (0, max_damping) are rejected [-]
  double cluster_frequency = 0.01;   ///< |f - f_cluster| / f_cluster below this to join [-]
  double cluster_mac = 0.9;          ///< MAC with the cluster's first pole at least this [-]
  double min_orders_fraction = 0.4;  ///< a cluster holds poles of at least this fraction of
                                     ///< the orders (and at least 3), else it is spurious [-]
  /// A cluster none of whose poles has a damping above this many of its std is spurious (not
  /// distinguishable from an undamped pole: noise) [-]; needs variance blocks.
  double damping_significance = 2.0;
  /// A pole whose frequency std exceeds this fraction of its half-power half-width (damping x
  /// frequency) is not resolved within its own resonance: it neither doubles an order nor enters
  /// the median or the representative, and a cluster with no resolved pole is spurious [-]; needs
  /// variance blocks.
  double frequency_resolution = 0.5;
  /// Below this damping ratio a pole inside a lines_only band is the order's line [-].
  double line_damping = 0.002;
  /// Two modes closer than this many std of their difference are marked unresolved [-].
  double resolution_sigmas = 2.0;
};

/// One identified mode: the representative of a cluster of stable poles.
struct IdentifiedMode {
  double frequency = 0.0;         ///< [Hz]
  double frequency_std = 0.0;     ///< [Hz] (NaN without variance blocks)
  double damping = 0.0;           ///< [-]
  double damping_std = 0.0;       ///< [-]
  Eigen::VectorXcd shape;         ///< over the channels, largest entry 1
  int order = 0;                  ///< model order of the representative
  int orders = 0;                 ///< model orders holding a pole of the cluster
  double frequency_spread = 0.0;  ///< max - min frequency over the cluster [Hz]
  /// True when an order put two poles into the cluster, fewer than half its poles agree with its
  /// median frequency within 2 of their std, or a neighbouring mode lies within resolution_sigmas
  /// std of the difference: close modes these channels and this record cannot separate; frequency
  /// and std then describe neither alone.
  bool unresolved = false;
};

/// What became of a pole in the selection.
enum class PoleStatus {
  kOrderBand,     ///< inside an excluded band: a removed order, set aside
  kInadmissible,  ///< damping outside (0, max_damping)
  kUnstable,      ///< no matching pole at the neighbouring orders
  kStable,        ///< stable, in a cluster found spurious
  kSelected,      ///< stable, in the cluster of a reported mode
};
/// "order band", "inadmissible", "unstable", "stable" or "selected".
const char* poleStatusName(PoleStatus s);

struct SelectionResult {
  std::vector<IdentifiedMode> modes;  ///< sorted by frequency
  /// Per pole of the SsiResult, in its order: what became of it, and the index into `modes` of the
  /// mode its cluster became (-1 otherwise).
  std::vector<PoleStatus> status;
  std::vector<int> mode_of;
  std::vector<Pole> order_poles;  ///< poles inside an excluded band: never reported as modes
  int spurious_clusters = 0;      ///< clusters from too few orders or with insignificant damping
};

/// Selects the modes among `ssi`'s poles; poles inside any `excluded` band (a removed mesh or
/// shaft order) are set aside as order_poles. Throws InvalidInput naming a threshold out of range.
SelectionResult selectModes(const SsiResult& ssi, const std::vector<FrequencyBand>& excluded = {},
                            const SelectionOptions& options = {});

}  // namespace drivetrain_stiffness::modal

#include "drivetrain_stiffness/modal/mode_matching.hpp"

#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness::modal {

const char* observabilityName(Observability o) {
  switch (o) {
    case Observability::kObservable: return "observable";
    case Observability::kAboveNyquist: return "above Nyquist";
    case Observability::kNoChannel: return "no channel sees it";
  }
  return "?";
}

MatchResult matchModes(const std::vector<IdentifiedMode>& identified,
                       const std::vector<PredictedMode>& predicted, double sample_rate,
                       const MatchOptions& o) {
  requirePositive("sample_rate", sample_rate);
  requireInOpenRange("matching.frequency_window", o.frequency_window, 0.0, 1.0);
  requireInClosedRange("matching.min_mac", o.min_mac, 0.0, 1.0);
  requireNonNegative("matching.visibility", o.visibility);
  const long channels = identified.empty() ? -1 : identified.front().shape.size();
  MatchResult out;
  for (size_t k = 0; k < predicted.size(); ++k) {
    const PredictedMode& p = predicted[k];
    const std::string field = "predicted[" + std::to_string(k) + "]";
    requirePositive(field + ".frequency", p.frequency);
    if (channels >= 0 && p.shape.size() != channels)
      throwInvalid(field + ".shape.size", static_cast<double>(p.shape.size()),
                   "must equal the channels " + std::to_string(channels));
    for (long c = 0; c < p.shape.size(); ++c) {
      requireFinite(field + ".shape.real", p.shape[c].real());
      requireFinite(field + ".shape.imag", p.shape[c].imag());
    }
    Observability obs = Observability::kObservable;
    if (p.frequency >= 0.5 * sample_rate)
      obs = Observability::kAboveNyquist;
    else if (p.shape.size() == 0 || p.shape.cwiseAbs().maxCoeff() < o.visibility)
      obs = Observability::kNoChannel;
    out.observability.push_back(obs);
    out.identified_of.push_back(-1);
  }
  // One to one: every candidate pair (within the window, MAC at least min_mac), the highest MAC
  // first; a pair whose identified or predicted mode is taken already is passed over.
  struct Candidate {
    double mac;
    size_t i, k;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < identified.size(); ++i)
    for (size_t k = 0; k < predicted.size(); ++k) {
      if (out.observability[k] != Observability::kObservable) continue;
      if (std::abs(identified[i].frequency - predicted[k].frequency) >
          o.frequency_window * predicted[k].frequency)
        continue;
      const double m = mac(identified[i].shape, predicted[k].shape);
      if (m >= o.min_mac) candidates.push_back({m, i, k});
    }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.mac > b.mac; });
  out.predicted_of.assign(identified.size(), -1);
  out.mac_of.assign(identified.size(), std::numeric_limits<double>::quiet_NaN());
  for (const Candidate& c : candidates) {
    if (out.predicted_of[c.i] >= 0 || out.identified_of[c.k] >= 0) continue;
    out.predicted_of[c.i] = static_cast<int>(c.k);
    out.mac_of[c.i] = c.mac;
    out.identified_of[c.k] = static_cast<int>(c.i);
  }
  return out;
}

}  // namespace drivetrain_stiffness::modal

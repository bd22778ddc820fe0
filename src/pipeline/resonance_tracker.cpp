#include "drivetrain_stiffness/pipeline/resonance_tracker.hpp"

#include <cmath>
#include <string>

namespace drivetrain_stiffness {

ResonanceTracker::ResonanceTracker(const RigConfig& rig, const StiffnessEstimator& estimator,
                                   const CalibrationStage& calibration, double threshold)
    : rig_(rig), estimator_(estimator), calibration_(calibration), threshold_(threshold) {}

bool ResonanceTracker::withinCourantFischerBounds(const std::array<double, 3>& springs,
                                                  const std::array<double, 3>& at_last,
                                                  double threshold) {
  // K = sum k_i B_i with B_i >= 0 and M fixed: springs within factors [lo, hi] bound every
  // undamped omega^2 within the same factors, each frequency within [sqrt(lo), sqrt(hi)]. Shrunk by
  // 1e-9 for the eigensolver's rounding (1e-15). Derivation and history: docs/resonance.md.
  const double tau = threshold, margin = 1e-9;
  const double hi = (1.0 + tau) * (1.0 + tau) * (1.0 - margin),
               lo = (1.0 - tau) * (1.0 - tau) * (1.0 + margin);
  bool within = true;
  for (int i = 0; i < 3 && within; ++i) {
    within = springs[i] <= hi * at_last[i] && springs[i] >= lo * at_last[i];
  }
  return within;
}

void ResonanceTracker::update(Stamp stamp, const StiffnessEstimate& estimate,
                              const DampingRatios& damping, const DynamicsEstimator& dynamics,
                              PipelineSink& sink) {
  try {
    const std::array<double, 2> kb = estimator_.shaftRadialStiffness();
    const std::array<double, 3> springs{kb[0], kb[1], estimate.mesh.mean};
    if (last_ && withinCourantFischerBounds(springs, springs_at_last_, threshold_)) return;
    const GearRotorParameters p = rigRotorParameters(rig_, estimator_.mesh(), kb, damping);
    ResonanceEstimate r;
    r.modes = modalAnalysis(p, estimate.mesh.mean);
    ++counters_.modal_updates;
    bool moved = !last_;
    for (std::size_t i = 0; !moved && i < r.modes.size(); ++i) {
      const double last = last_->modes[i].natural_frequency;
      moved = std::abs(r.modes[i].natural_frequency - last) > threshold_ * last;
    }
    if (!moved) return;
    for (const Mode& m : r.modes) {
      if (!std::isfinite(m.natural_frequency) || !std::isfinite(m.damping_ratio) ||
          !std::isfinite(m.damped_frequency)) {
        throw InvalidInput(
            "resonance: a modal result is not finite (not published)");  // never NaN on a topic
      }
    }
    double margin = 0.0;
    r.floquet_valid = dynamics.floquetMargin(&margin) && std::isfinite(margin);
    r.floquet_margin = r.floquet_valid ? margin : 0.0;
    last_ = r;
    springs_at_last_ = springs;
    sink.resonance(stamp, r, calibration_.resonanceBands(r));
    ++counters_.resonance_out;
  } catch (const Error& e) {
    ++counters_.resonance_errors;
    events_.record(std::string("resonance: ") + e.what());
  }
}

}  // namespace drivetrain_stiffness

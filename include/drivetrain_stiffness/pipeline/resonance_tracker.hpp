// The resonance stage: the natural frequencies after each stiffness update, republished when one
// moved by more than ~resonance_threshold (docs/resonance.md "Node").
#pragma once

#include <array>
#include <optional>

#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

class ResonanceTracker {
 public:
  /// `threshold` [-] in (0, 1). Keeps references to everything but the threshold.
  ResonanceTracker(const RigConfig& rig, const StiffnessEstimator& estimator,
                   const CalibrationStage& calibration, double threshold);
  /// True when every spring [N/m] is within [(1 - threshold)^2, (1 + threshold)^2] (shrunk by 1e-9)
  /// of `at_last`: by Courant-Fischer no natural frequency can have moved by more than threshold.
  static bool withinCourantFischerBounds(const std::array<double, 3>& springs,
                                         const std::array<double, 3>& at_last, double threshold);
  /// After a stiffness update: a moved estimate goes to sink.resonance; an Error is counted in
  /// dynamics_errors and nothing published.
  void update(Stamp stamp, const StiffnessEstimate& estimate, const DampingRatios& damping,
              const DynamicsEstimator& dynamics, PipelineSink& sink);
  /// The next update publishes whatever it finds (a reset, a damping change).
  void forget() { last_.reset(); }
  /// The last published estimate.
  const std::optional<ResonanceEstimate>& last() const { return last_; }
  const ResonanceCounters& counters() const { return counters_; }
  /// The last error, with its reason.
  const EventLog& events() const { return events_; }

 private:
  const RigConfig& rig_;
  const StiffnessEstimator& estimator_;
  const CalibrationStage& calibration_;
  double threshold_;
  ResonanceCounters counters_;
  EventLog events_;
  std::optional<ResonanceEstimate> last_;
  std::array<double, 3> springs_at_last_{};  ///< [N/m]
};

}  // namespace drivetrain_stiffness

// The resonance stage: after each stiffness update the natural frequencies at the new operating
// point, republished when one moved by more than ~resonance_threshold. The modal analysis is
// skipped where Courant-Fischer proves no frequency can have moved that far (docs/resonance.md,
// "Node"). ROS-free.
#pragma once

#include <array>
#include <optional>

#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

class ResonanceTracker {
 public:
  /// `threshold` [-] in (0, 1): the relative frequency change that republishes. Keeps references
  /// to `rig` (masses, geometry), `estimator` (bearing and mesh stiffness), `calibration` (the
  /// bands) and `counters` (modal_updates, resonance_out, dynamics_errors, last_event).
  ResonanceTracker(const RigConfig& rig, const StiffnessEstimator& estimator,
                   const CalibrationStage& calibration, double threshold,
                   PipelineCounters& counters);
  /// The Courant-Fischer shortcut: true when every spring (bearing per shaft, mean mesh) [N/m] is
  /// within [(1 - threshold)^2, (1 + threshold)^2] (shrunk by 1e-9) of its value at the last
  /// publication, so no natural frequency can have moved by more than `threshold`.
  static bool withinCourantFischerBounds(const std::array<double, 3>& springs,
                                         const std::array<double, 3>& at_last, double threshold);
  /// After a stiffness update at `stamp`: `estimate` the new one, `damping` the run-time ratios,
  /// `dynamics` for the Floquet margin. A moved estimate goes to sink.resonance; the library's own
  /// errors (a non-finite mode among them) are counted in dynamics_errors, nothing published.
  void update(Stamp stamp, const StiffnessEstimate& estimate, const DampingRatios& damping,
              const DynamicsEstimator& dynamics, PipelineSink& sink);
  /// The next update publishes whatever it finds (a reset, a damping change).
  void forget() { last_.reset(); }
  /// The last published estimate (none since forget()).
  const std::optional<ResonanceEstimate>& last() const { return last_; }

 private:
  const RigConfig& rig_;
  const StiffnessEstimator& estimator_;
  const CalibrationStage& calibration_;
  double threshold_;
  PipelineCounters& counters_;
  std::optional<ResonanceEstimate> last_;
  std::array<double, 3> springs_at_last_{};  ///< the springs at the last publication [N/m]
};

}  // namespace drivetrain_stiffness

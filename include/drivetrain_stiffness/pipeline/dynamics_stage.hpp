// The dynamics stage: the 3-DOF model between inputs under the own-stamp, gap and
// failed-integration rules (docs/ros_api.md); each sample to the SampleConsumers in order.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/sample_consumer.hpp"

namespace drivetrain_stiffness {

class DynamicsStage {
 public:
  /// The model of `rig` on the estimator's stiffness. Keeps references to `estimator`, `phase` and
  /// `counters`. Throws InvalidInput naming the field.
  DynamicsStage(std::shared_ptr<const RigConfig> rig, const StiffnessEstimator& estimator,
                const PipelineOptions& options, Fidelity fidelity, PhaseSource& phase,
                PipelineCounters& counters);
  /// Each sample goes to `consumer` after those added before (kept by reference).
  void addConsumer(SampleConsumer& consumer) { consumers_.push_back(&consumer); }
  DynamicsEstimator& model() { return model_; }
  const DynamicsEstimator& model() const { return model_; }

  /// A torque [N*m] held from `stamp`; a stopped model restarts at equilibrium under it (false).
  bool takeTorque(Stamp stamp, double torque, PipelineSink& sink);
  /// The estimator's bearing stiffness from `stamp` on.
  void takeBearingStiffness(Stamp stamp, PipelineSink& sink);
  /// Runs the model up to `stamp`; false if stopped, past it, a gap away or failed (counted).
  bool advanceTo(Stamp stamp, PipelineSink& sink);
  /// The gap rule: `stamp` more than ~max_gap after the model's time stops it (counted).
  void stopAfterGap(Stamp stamp);
  /// Follows the phase source's anchor from `stamp` (or the model's time, if later).
  void followAnchor(Stamp stamp);
  /// Stopped until the next torque, at the estimator's bearing stiffness.
  void reset();
  /// Counts `e` in dynamics_errors and last_event.
  void error(const std::string& where, const Error& e);

 private:
  void restart(Stamp stamp, double torque);
  void stop();
  /// advanceTo(t), each sample to the consumers (throws what advanceTo throws).
  void emitUpTo(double t, PipelineSink& sink);

  const StiffnessEstimator& estimator_;
  PhaseSource& phase_;
  PipelineCounters& counters_;
  DynamicsEstimator model_;
  double max_gap_;
  std::vector<SampleConsumer*> consumers_;
  double advance_mesh_frequency_ = 0.0;  ///< [Hz] during the current emitUpTo
  Stamp epoch_;                          ///< the model's time 0
};

}  // namespace drivetrain_stiffness

// The dynamics stage: the 3-DOF model (DynamicsEstimator) integrated between inputs on stamps,
// each input taking effect at its own stamp (the own-stamp rule), a long gap restarting the model
// instead of integrating it (the gap rule), a failed integration restarting it (the integration
// rule); every output sample handed, on its exact stamp, to the SampleConsumers in the order they
// were added. Rules: docs/ros_api.md, "Time and input rules". ROS-free.
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
  /// The model of `rig` (which needs a dynamics block) at the estimator's bearing stiffness and on
  /// its mesh table, ~output_rate [Hz], ~motion_slices, ~max_gap [s] of `options`, `fidelity`.
  /// Keeps references to `estimator` (the bearing stiffness it takes up), `phase` (the motion it
  /// follows; its origin restarts with the model) and `counters` (dynamics_errors, gap_restarts,
  /// simulated_s, last_event). Throws InvalidInput for a rig or option the model refuses.
  DynamicsStage(std::shared_ptr<const RigConfig> rig, const StiffnessEstimator& estimator, const PipelineOptions& options,
                Fidelity fidelity, PhaseSource& phase, PipelineCounters& counters);
  /// Each output sample goes to `consumer` after those added before (kept by reference).
  void addConsumer(SampleConsumer& consumer) { consumers_.push_back(&consumer); }
  DynamicsEstimator& model() { return model_; }
  const DynamicsEstimator& model() const { return model_; }

  /// A torque input [N*m] accepted at `stamp`: the model runs up to it with what was held, then
  /// holds it from there; stopped (or after a gap), the model restarts at equilibrium under it.
  /// Returns false when it restarted the model cleanly (RigPipeline's held torque then stays).
  bool takeTorque(Stamp stamp, double torque, PipelineSink& sink);
  /// The estimator's bearing stiffness from `stamp` on (after a gap the model stops first).
  void takeBearingStiffness(Stamp stamp, PipelineSink& sink);
  /// Runs the model up to `stamp` with what is held; false if stopped, already past it, or a gap
  /// away (a failure is counted and stops the model).
  bool advanceTo(Stamp stamp, PipelineSink& sink);
  /// The gap rule: an input more than ~max_gap after the model's time stops it (counted); the next
  /// torque input restarts it.
  void stopAfterGap(Stamp stamp);
  /// The model follows the phase source's anchor from `stamp` (or its own time, if later) on.
  void followAnchor(Stamp stamp);
  /// Stopped until the next torque input, at the estimator's bearing stiffness (a pipeline reset).
  void reset();
  /// The library's own error `e` counted in dynamics_errors, "`where`: reason" in last_event.
  void error(const std::string& where, const Error& e);

 private:
  void restart(Stamp stamp, double torque);
  void stop();
  /// advanceTo(t) handing each sample to the consumers (throws what advanceTo throws).
  void emitUpTo(double t, PipelineSink& sink);

  const StiffnessEstimator& estimator_;
  PhaseSource& phase_;
  PipelineCounters& counters_;
  DynamicsEstimator model_;
  double max_gap_;
  std::vector<SampleConsumer*> consumers_;
  double advance_mesh_frequency_ = 0.0;  ///< [Hz] the model's during the current emitUpTo
  /// The model runs on seconds since this stamp (the last restart): at a 1.7e9 s epoch a double
  /// resolves only 2.4e-7 s, enough to put an input exactly on a grid point one sample short.
  Stamp epoch_;
};

}  // namespace drivetrain_stiffness

// The dynamics stage: the 3-DOF model between inputs under the own-stamp, gap and
// failed-integration rules (docs/ros_api.md); each sample to the SampleConsumers in order. The
// pipeline decides when it advances and what it follows; the stage knows no phase source.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/sample_consumer.hpp"

namespace drivetrain_stiffness {

/// What DynamicsStage::advanceTo did.
enum class Advance {
  kAdvanced,     ///< integrated up to the stamp
  kStopped,      ///< not running (before the first torque, after a gap, a failure or a reset)
  kAlreadyPast,  ///< another stream took the model to the stamp or past it
  kGap,          ///< more than ~max_gap ahead: left to the gap rule
  kFailed,       ///< the integration failed (counted): stopped until the next torque input
};

/// What DynamicsStage::takeTorque did with the torque.
enum class TorqueTaken {
  kHeld,       ///< held from the input's stamp by the running model
  kRestarted,  ///< the stopped model restarted at the input's stamp, at equilibrium under it
};

class DynamicsStage {
 public:
  /// A moment on both clocks: the model's time t [s] and its stamp.
  struct Moment {
    double t = 0.0;
    Stamp stamp;
  };

  /// The model of `rig` on the estimator's stiffness. Keeps a reference to `estimator`. Throws
  /// InvalidInput naming the field.
  DynamicsStage(std::shared_ptr<const RigConfig> rig, const StiffnessEstimator& estimator,
                const PipelineOptions& options, Fidelity fidelity);
  /// Each sample goes to `consumer` after those added before (kept by reference).
  void addConsumer(SampleConsumer& consumer) { consumers_.push_back(&consumer); }
  DynamicsEstimator& dynamics() { return dynamics_; }
  const DynamicsEstimator& dynamics() const { return dynamics_; }
  const DynamicsCounters& counters() const { return counters_; }
  /// The last gap restart or error, with its reason.
  const EventLog& events() const { return events_; }

  /// Runs the model up to `stamp`, each sample to the consumers; a failure is counted and stops it.
  Advance advanceTo(Stamp stamp, PipelineSink& sink);
  /// The gap rule: `stamp` more than ~max_gap after the model's time stops it (counted).
  void stopAfterGap(Stamp stamp);
  /// The estimator's bearing stiffness, from `stamp` if advanceTo(stamp) gave `advanced`, else from
  /// the model's time.
  void takeBearingStiffness(Stamp stamp, Advance advanced);
  /// A torque [N*m] held from `stamp` (after advanceTo(stamp)); a stopped model restarts under it.
  TorqueTaken takeTorque(Stamp stamp, double torque);
  /// `stamp`, or the model's time if that is later (another stream took it past); none if stopped.
  std::optional<Moment> momentAtOrAfter(Stamp stamp) const;
  /// Measured motion from `at`: mesh phase [turns] and mesh frequency [Hz] (an error is counted).
  void followMotion(const Moment& at, double mesh_turns, double mesh_frequency);
  /// Stopped until the next torque, at the estimator's bearing stiffness.
  void reset();

 private:
  void restart(Stamp stamp, double torque);
  void stop();
  /// Counts `e` in model_errors and the events.
  void error(const std::string& where, const Error& e);
  /// advanceTo(t), each sample to the consumers (throws what advanceTo throws).
  void emitUpTo(double t, PipelineSink& sink);

  const StiffnessEstimator& stiffness_;
  DynamicsCounters counters_;
  EventLog events_;
  DynamicsEstimator dynamics_;
  double max_gap_;
  std::vector<SampleConsumer*> consumers_;
  double advance_mesh_frequency_ = 0.0;  ///< [Hz] during the current emitUpTo
  Stamp epoch_;                          ///< the model's time 0
};

}  // namespace drivetrain_stiffness

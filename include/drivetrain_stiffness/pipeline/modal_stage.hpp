// The modal identification stage: each time the vibration record holds ~vibration_record of new
// samples, one identification of it (modal_identification.hpp), run on a worker thread (the node)
// or in the caller's (a replay). Its result is applied at the first accepted vibration block
// stamped kApplyDelay after the record's end, or at finish(): the same input either way, so a
// replay is bit-identical to the live run. The matched frequencies update the calibration
// (docs/vibration.md "Identification in the pipeline").
#pragma once

#include <cstdint>
#include <future>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/calibration_stage.hpp"
#include "drivetrain_stiffness/pipeline/modal_identification.hpp"
#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/vibration_input.hpp"

namespace drivetrain_stiffness {

class ModalStage {
 public:
  /// [s] of record time between a record's end and its result's use: room for the worker.
  static constexpr double kApplyDelay = 0.5;

  /// Keeps references to everything; identifies with options.modal_max_order on a worker thread
  /// when options.modal_worker.
  ModalStage(const RigConfig& rig, const VibrationInput& input, const PhaseSource& phase,
             const StiffnessEstimator& estimator, CalibrationStage& calibration,
             const PipelineOptions& options);
  ~ModalStage();  ///< waits for a running identification
  ModalStage(const ModalStage&) = delete;
  ModalStage& operator=(const ModalStage&) = delete;

  /// After the input took a block of `frames` frames stamped `stamp` (its first frame): a due
  /// result applied, the frames and their angles written into the record being filled, a full
  /// record handed to the identification. Allocates only when a record starts (two buffers of
  /// ~vibration_record) and when an identification starts (its thread and result).
  void afterBlock(Stamp stamp, std::size_t frames, double held_torque, PipelineSink& sink);
  /// The input ended: the pending identification, if any, is applied (stamped as it would have
  /// been).
  void finish(PipelineSink& sink);
  /// Forgets the record's angles and any pending identification (a pipeline reset).
  void reset();
  /// An identification is running or waits to be applied.
  bool pending() const { return pending_.valid(); }
  const ModalCounters& counters() const { return counters_; }
  /// The last record that could not be identified, with the reason.
  const EventLog& events() const { return events_; }

 private:
  struct Outcome {
    ModalReport report;
    std::string error;  ///< non-empty: the identification threw this
  };
  /// Frames [first, first + count) of the block (the newest of the input's record) into the
  /// buffer being filled, at `stamp` + first / rate.
  void fill(Stamp stamp, std::size_t first, std::size_t count);
  void start(double held_torque);
  void predict(ModalJob& job, double torque) const;
  void apply(Stamp stamp, PipelineSink& sink);

  const RigConfig& rig_;
  const VibrationInput& input_;
  const PhaseSource& phase_;
  const StiffnessEstimator& estimator_;
  CalibrationStage& calibration_;
  ModalCounters counters_;
  EventLog events_;
  bool enabled_, worker_;
  int max_order_, block_rows_, skipped_lags_;
  double band_;
  /// Two records: one filled block by block, the other read by a pending identification.
  std::array<ModalJob, 2> jobs_;
  std::size_t filling_ = 0;       ///< the buffer being filled
  std::size_t filled_ = 0;        ///< its frames so far
  std::size_t block_frames_ = 0;  ///< the frames of the block being taken
  std::future<Outcome> pending_;  ///< reads jobs_[1 - filling_] until apply()
  Outcome spent_;                 ///< the last result applied, until the next start() frees it
  Stamp apply_at_;
};

}  // namespace drivetrain_stiffness

// Each stage's own counters and last event; RigPipeline merges them into PipelineCounters
// (pipeline_outputs.hpp) under the keys of /diagnostics and summary.json.
#pragma once

#include <cstdint>
#include <string>

namespace drivetrain_stiffness {

/// A stage's last event (a refusal, a reset, an error) with its place among every stage's events.
class EventLog {
 public:
  /// `text` is the stage's last event, later than every event recorded before it by any EventLog.
  void record(std::string text);
  const std::string& last() const { return text_; }
  /// 0 before the first event; larger for a later event (one sequence for the whole process).
  std::uint64_t order() const { return order_; }

 private:
  std::string text_;
  std::uint64_t order_ = 0;
};

/// InputGate: every input accepted, refused (by reason) or dropped, and the resets it called.
struct GateCounters {
  std::uint64_t accepted_torque = 0, rejected_torque = 0;
  std::uint64_t accepted_preload = 0, rejected_preload = 0;
  std::uint64_t zero_stamps = 0, out_of_order = 0, invalid_values = 0, unreachable_loads = 0;
  std::uint64_t wrong_frames = 0, stamps_out_of_range = 0;
  std::uint64_t dropped_torque = 0, dropped_preload = 0;
  std::uint64_t accepted_motion = 0, rejected_motion = 0, dropped_motion = 0;
  std::uint64_t accepted_vibration = 0, rejected_vibration = 0, dropped_vibration = 0;  ///< blocks
  std::uint64_t clock_resets = 0, stamp_resets = 0;
};

/// PhaseSource: the encoders rule's time-outs and gear-ratio mismatches.
struct PhaseCounters {
  std::uint64_t motion_timeouts = 0, gear_ratio_mismatches = 0;
};

/// DynamicsStage: restarts after a gap, errors of the model, model time integrated.
struct DynamicsCounters {
  std::uint64_t gap_restarts = 0;
  std::uint64_t model_errors = 0;  ///< counted under dynamics_errors
  double simulated_s = 0.0;        ///< [s]
};

/// ResonanceTracker: modal analyses, published estimates, errors.
struct ResonanceCounters {
  std::uint64_t modal_updates = 0, resonance_out = 0;
  std::uint64_t resonance_errors = 0;  ///< counted under dynamics_errors
};

/// RigPipeline's stiffness output: published, coalesced, refused by the sink, shed inputs.
struct StiffnessOutputCounters {
  std::uint64_t stiffness_out = 0, stiffness_coalesced = 0, stiffness_refused = 0;
  std::uint64_t stiffness_shed = 0;
};

/// The sample consumers' outputs.
struct TeOutputCounters {
  std::uint64_t te_out = 0;
};
struct SpectrumCounters {
  std::uint64_t spectra_out = 0;
};
struct MeshPeriodCounters {
  std::uint64_t mesh_period_stats_out = 0;
};

/// CalibrationStage: messages published, errors counted.
struct CalibrationCounters {
  std::uint64_t measured_te_out = 0, calibration_out = 0, calibration_errors = 0;
};

/// ModalStage: identifications published, records that could not be identified.
struct ModalCounters {
  std::uint64_t modal_out = 0, modal_errors = 0;
};

/// VibrationInput: what the vibration block rules counted.
struct VibrationCounters {
  std::uint64_t samples = 0;           ///< accepted samples per channel (frames)
  std::uint64_t gaps = 0;              ///< a block later than the previous one's end: new record
  std::uint64_t overlaps = 0;          ///< a block earlier than the previous one's end: refused
  std::uint64_t rate_changes = 0;      ///< another sample rate: new record
  std::uint64_t channel_changes = 0;   ///< other channel names: new record
  std::uint64_t unknown_channels = 0;  ///< channels of accepted blocks that name no support
};

}  // namespace drivetrain_stiffness

// What the pipeline hands out, as plain values: its sink's inputs and its counters.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/modal_identification.hpp"
#include "drivetrain_stiffness/spectral/spectrum.hpp"

namespace drivetrain_stiffness {

/// The resonance estimate at an operating point.
struct ResonanceEstimate {
  std::array<Mode, 3> modes;
  bool floquet_valid = false;
  double floquet_margin = 0.0;  ///< 1 - max |mu|; 0 when not valid
};

/// The dynamic TE and mesh force over a block of whole mesh periods (docs/pipeline.md "Mesh-period
/// statistics").
struct MeshPeriodStatistics {
  Stamp start, end;           ///< the block's first and last samples
  double duration = 0.0;      ///< [s]
  std::uint32_t periods = 0;  ///< net
  std::uint32_t samples = 0;  ///< in [start, end)
  double te_mean = 0.0, te_rms = 0.0, te_peak_to_peak = 0.0;                          ///< [m]
  double mesh_force_mean = 0.0, mesh_force_rms = 0.0, mesh_force_peak_to_peak = 0.0;  ///< [N]
  double mesh_frequency = 0.0;                                                        ///< [Hz]
  double torque = 0.0;                                                                ///< [N*m]
};

/// What a TE sample's tf frames and markers need.
struct SampleContext {
  double pinion_angle = 0.0;                     ///< [rad] the encoders' (no offset)
  const ResonanceEstimate* resonance = nullptr;  ///< the last published; valid during the call
};

/// The TE spectrum's strongest lines (fixed storage).
struct SpectrumPeaks {
  static constexpr std::size_t kMaxPeaks = 3;
  std::array<SpectralPeak, kMaxPeaks> peaks{};  ///< the first `count`, strongest first
  std::size_t count = 0;
  double resolution = 0.0;      ///< [Hz]
  double window_seconds = 0.0;  ///< [s]
};

/// Receives the pipeline's outputs; every method optional. A sink's Error is counted.
class PipelineSink {
 public:
  virtual ~PipelineSink() = default;
  /// After an accepted input, at most ~stiffness_rate; `bands` of zero width uncalibrated.
  virtual void stiffness(Stamp /*stamp*/, const StiffnessEstimate& /*estimate*/,
                         const CalibrationBands& /*bands*/) {}
  /// One TE sample on the output grid, at its exact stamp.
  virtual void transmissionError(Stamp /*stamp*/, const DynamicsSample& /*sample*/,
                                 const SampleContext& /*context*/) {}
  /// New spectrum peaks, at the newest sample's stamp.
  virtual void spectrum(Stamp /*stamp*/, const SpectrumPeaks& /*peaks*/) {}
  /// The estimate moved by more than ~resonance_threshold, or after a reset.
  virtual void resonance(Stamp /*stamp*/, const ResonanceEstimate& /*estimate*/,
                         const CalibrationBands& /*bands*/) {}
  /// One reading's measured TE beside the calibrated model's.
  virtual void measuredTe(Stamp /*stamp*/, const MeasuredTeSample& /*sample*/) {}
  /// The calibration after each closed window, at the closing reading's stamp.
  virtual void calibration(Stamp /*stamp*/, const CalibrationEstimate& /*estimate*/) {}
  /// A closed block of whole mesh periods, at its end sample's stamp.
  virtual void meshPeriod(Stamp /*stamp*/, const MeshPeriodStatistics& /*stats*/) {}
  /// One vibration record's modal identification, at the record's last sample's stamp.
  virtual void modalIdentification(Stamp /*stamp*/, const ModalReport& /*report*/) {}
};

/// What the vibration block rules counted (VibrationInput).
struct VibrationCounters {
  std::uint64_t samples = 0;           ///< accepted samples per channel (frames)
  std::uint64_t gaps = 0;              ///< a block later than the previous one's end: new record
  std::uint64_t overlaps = 0;          ///< a block earlier than the previous one's end: refused
  std::uint64_t rate_changes = 0;      ///< another sample rate: new record
  std::uint64_t channel_changes = 0;   ///< other channel names: new record
  std::uint64_t unknown_channels = 0;  ///< channels of accepted blocks that name no support
};

/// Everything the pipeline saw (docs/ros_api.md, /diagnostics).
struct PipelineCounters {
  std::uint64_t accepted_torque = 0, rejected_torque = 0;
  std::uint64_t accepted_preload = 0, rejected_preload = 0;
  std::uint64_t zero_stamps = 0, out_of_order = 0, invalid_values = 0, unreachable_loads = 0;
  std::uint64_t wrong_frames = 0, stamps_out_of_range = 0;
  std::uint64_t dropped_torque = 0, dropped_preload = 0;
  std::uint64_t accepted_motion = 0, rejected_motion = 0, dropped_motion = 0;
  std::uint64_t accepted_vibration = 0, rejected_vibration = 0, dropped_vibration = 0;  ///< blocks
  VibrationCounters vibration;
  std::uint64_t motion_timeouts = 0, gear_ratio_mismatches = 0;
  std::uint64_t stiffness_shed = 0;
  std::uint64_t clock_resets = 0, stamp_resets = 0, gap_restarts = 0;
  std::uint64_t dynamics_errors = 0;
  std::uint64_t stiffness_out = 0, stiffness_coalesced = 0;
  std::uint64_t stiffness_refused = 0;
  std::uint64_t te_out = 0, spectra_out = 0, resonance_out = 0;
  std::uint64_t modal_updates = 0;
  std::uint64_t measured_te_out = 0, calibration_out = 0;
  std::uint64_t mesh_period_stats_out = 0;
  std::uint64_t calibration_errors = 0;
  std::uint64_t modal_out = 0;     ///< modal identifications published
  std::uint64_t modal_errors = 0;  ///< records the identification could not identify
  double simulated_s = 0.0;        ///< [s] model time integrated
  std::string last_event;          ///< the last rejection or reset, with its reason
};

/// The counters by the names /diagnostics and drivetrain_replay's summary use.
std::vector<std::pair<std::string, std::uint64_t>> namedCounters(const PipelineCounters& c);

}  // namespace drivetrain_stiffness

// What the pipeline hands out: the values its sink receives (estimates, samples with their
// context, spectrum lines, mesh-period statistics, calibration) and the counters of everything it
// saw. Plain values, ROS-free.
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
#include "drivetrain_stiffness/spectral/spectrum.hpp"

namespace drivetrain_stiffness {

/// The resonance estimate at an operating point.
struct ResonanceEstimate {
  std::array<Mode, 3> modes;
  bool floquet_valid = false;
  double floquet_margin = 0.0;  ///< 1 - max |Floquet multiplier| (0 when not valid)
};

/// Statistics of the dynamic TE and the mesh force over a block of whole mesh periods (issue 12;
/// MeshPeriodStage). Block and estimators: docs/pipeline.md, "Mesh-period statistics" (the mesh
/// force's mean is a momentum balance, not the samples' mean). Named apart from the message
/// drivetrain_stiffness/MeshPeriodStats, which shares the namespace.
struct MeshPeriodStatistics {
  Stamp start, end;               ///< the block's first and last output samples
  double duration = 0.0;          ///< end - start [s]
  std::uint32_t periods = 0;      ///< whole mesh periods in the block (net)
  std::uint32_t samples = 0;      ///< output samples in [start, end) (the end sample starts the next block)
  double te_mean = 0.0, te_rms = 0.0, te_peak_to_peak = 0.0;                          ///< [m]
  double mesh_force_mean = 0.0, mesh_force_rms = 0.0, mesh_force_peak_to_peak = 0.0;  ///< [N]
  double mesh_frequency = 0.0;    ///< [Hz]
  double torque = 0.0;            ///< [N*m]
};

/// What the tf frames and markers of a transmission-error sample need besides the sample: plain
/// values of that moment, so that a sink never asks the pipeline back in the middle of an advance.
struct SampleContext {
  /// [rad] at the sample's stamp, as the encoders count it (RigPipeline::encoderPinionAngle: without
  /// the ~mesh_phase_offset that the mesh phase carries), or the nominal angle without encoders.
  double pinion_angle = 0.0;
  /// The last published resonance estimate, null when there is none since the last reset; points
  /// at the pipeline's copy, valid during the call only.
  const ResonanceEstimate* resonance = nullptr;
};

/// The TE spectrum's strongest lines over the sliding window, copied out of it (fixed storage: no
/// allocation per spectrum).
struct SpectrumPeaks {
  static constexpr std::size_t kMaxPeaks = 3;  ///< the lines the pipeline keeps (te_spectrum)
  std::array<SpectralPeak, kMaxPeaks> peaks{};  ///< the first `count`, strongest first
  std::size_t count = 0;
  double resolution = 0.0;      ///< [Hz] bin spacing, 1 / window_seconds
  double window_seconds = 0.0;  ///< [s]
};

/// Receives the pipeline's outputs as plain values; every method is optional. A sink may throw the
/// library's own Error (a message it refuses, e.g. a non-finite number): the pipeline counts it.
class PipelineSink {
 public:
  virtual ~PipelineSink() = default;
  /// After an accepted input (throttled to ~stiffness_rate); stamp = the input's. `bands`: the
  /// calibrated stiffness at the estimate's torque with its 95 % bounds, or without a calibration
  /// the drawing's model (mesh: estimate.mesh.mean; bearings: the shafts' radial stiffness) with
  /// bounds of zero width; the natural frequencies are not filled.
  virtual void stiffness(Stamp /*stamp*/, const StiffnessEstimate& /*estimate*/, const CalibrationBands& /*bands*/) {}
  /// One transmission-error sample on the output grid, at `stamp` (exact; sample.t = stamp.toSec()).
  virtual void transmissionError(Stamp /*stamp*/, const DynamicsSample& /*sample*/, const SampleContext& /*context*/) {}
  /// New TE spectrum peaks; stamp of the newest sample in the window.
  virtual void spectrum(Stamp /*stamp*/, const SpectrumPeaks& /*peaks*/) {}
  /// The resonance estimate moved by more than the threshold (or after a reset); stamp = the
  /// input's. `bands`: the calibrated stiffness and natural frequencies at the current torque with
  /// their 95 % bounds, or without a calibration the estimate's frequencies with bounds of zero
  /// width (the stiffness entries then unfilled).
  virtual void resonance(Stamp /*stamp*/, const ResonanceEstimate& /*estimate*/, const CalibrationBands& /*bands*/) {}
  /// One encoder reading's measured TE (baseline and shaft orders removed) beside the calibrated
  /// model's; stamp = the reading's (rule 11).
  virtual void measuredTe(Stamp /*stamp*/, const MeasuredTeSample& /*sample*/) {}
  /// The calibration after a closed window (every window, whatever its outcome); stamp = the
  /// reading that closed it.
  virtual void calibration(Stamp /*stamp*/, const CalibrationEstimate& /*estimate*/) {}
  /// One block of whole mesh periods closed (MeshPeriodStatistics); stamp = its end sample's.
  virtual void meshPeriod(Stamp /*stamp*/, const MeshPeriodStatistics& /*stats*/) {}
};

/// Counters of everything the pipeline saw; nothing is dropped without being counted here.
struct PipelineCounters {
  std::uint64_t accepted_torque = 0, rejected_torque = 0;
  std::uint64_t accepted_preload = 0, rejected_preload = 0;
  std::uint64_t zero_stamps = 0, out_of_order = 0, invalid_values = 0, unreachable_loads = 0;
  std::uint64_t wrong_frames = 0, stamps_out_of_range = 0;
  std::uint64_t dropped_torque = 0, dropped_preload = 0;  ///< numbered messages that never arrived
  std::uint64_t accepted_motion = 0, rejected_motion = 0, dropped_motion = 0;  ///< joint_states
  std::uint64_t motion_timeouts = 0, gear_ratio_mismatches = 0;
  std::uint64_t stiffness_shed = 0;  ///< backlogged torque inputs: dynamics only, no stiffness update
  std::uint64_t clock_resets = 0, stamp_resets = 0, gap_restarts = 0;
  std::uint64_t dynamics_errors = 0;
  std::uint64_t stiffness_out = 0, stiffness_coalesced = 0;  ///< published, and skipped by ~stiffness_rate
  std::uint64_t stiffness_refused = 0;  ///< stiffness messages the sink refused (its reason in last_event)
  std::uint64_t te_out = 0, spectra_out = 0, resonance_out = 0;
  std::uint64_t modal_updates = 0;  ///< modal analyses actually run (see RigPipeline::updateResonance)
  std::uint64_t measured_te_out = 0, calibration_out = 0;  ///< published (rule 11)
  std::uint64_t mesh_period_stats_out = 0;  ///< blocks of whole mesh periods published (MeshPeriodStatistics)
  std::uint64_t calibration_errors = 0;  ///< windows the calibration could not evaluate (last_event says why)
  double simulated_s = 0.0;         ///< model time integrated
  std::string last_event;           ///< last rejection or reset, with its reason
};

/// The counters by the names /diagnostics and drivetrain_replay's summary use (one list for both).
std::vector<std::pair<std::string, std::uint64_t>> namedCounters(const PipelineCounters& c);

}  // namespace drivetrain_stiffness

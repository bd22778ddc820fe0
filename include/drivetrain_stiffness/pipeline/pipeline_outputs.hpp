// What the pipeline hands out, as plain values: its sink's inputs and its merged counters.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "drivetrain_stiffness/calibration/calibrator.hpp"
#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/modal_identification.hpp"
#include "drivetrain_stiffness/pipeline/stage_counters.hpp"
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

/// Every stage's counters merged by RigPipeline::counters(), and the last event of any stage
/// (docs/ros_api.md, /diagnostics).
struct PipelineCounters : GateCounters,
                          PhaseCounters,
                          DynamicsCounters,
                          ResonanceCounters,
                          StiffnessOutputCounters,
                          TeOutputCounters,
                          SpectrumCounters,
                          MeshPeriodCounters,
                          CalibrationCounters,
                          ModalCounters {
  VibrationCounters vibration;
  std::uint64_t dynamics_errors = 0;  ///< model_errors + resonance_errors
  std::string last_event;             ///< the last rejection, reset or error, with its reason
};

/// The counters by the names /diagnostics and drivetrain_replay's summary use.
std::vector<std::pair<std::string, std::uint64_t>> namedCounters(const PipelineCounters& c);

}  // namespace drivetrain_stiffness

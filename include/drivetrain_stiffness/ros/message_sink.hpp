// The pipeline's outputs as ROS messages: converts each output (message_conversion.hpp), adds the
// tf frames and rviz markers at ~tf_rate (decided on sample time, so a replay makes the same
// choices as the live node), and hands everything to emit*(), which the node implements by
// publishing and the replay tool by writing a bag and CSV files.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <visualization_msgs/MarkerArray.h>

#include "drivetrain_stiffness/ros/message_conversion.hpp"
#include "drivetrain_stiffness/ros/rig_visualization.hpp"

namespace drivetrain_stiffness {

/// What the sink needs beyond the pipeline's run-time settings (exaggeration and tf rate live in
/// RuntimeSettings, read from the pipeline at each output).
struct OutputSettings {
  VisualizationFrames frames;
};

class MessageSink : public PipelineSink {
 public:
  /// The rig geometry and the start-up run-time settings (exaggeration, tf rate) are read from the
  /// pipeline here, once; afterwards the sink works on the values each output brings.
  MessageSink(const RigPipeline& pipeline, const OutputSettings& settings);

  void stiffness(Stamp stamp, const StiffnessEstimate& estimate,
                 const CalibrationBands& bands) override;
  void transmissionError(Stamp stamp, const DynamicsSample& sample,
                         const SampleContext& context) override;
  void spectrum(Stamp stamp, const SpectrumPeaks& peaks) override;
  void resonance(Stamp stamp, const ResonanceEstimate& estimate,
                 const CalibrationBands& bands) override;
  void measuredTe(Stamp stamp, const MeasuredTeSample& sample) override;
  void calibration(Stamp stamp, const CalibrationEstimate& estimate) override;
  void meshPeriod(Stamp stamp, const MeshPeriodStatistics& stats) override;
  void modalIdentification(Stamp stamp, const ModalReport& report) override;

  /// New run-time settings, as applied to the pipeline (RigPipeline::apply): the sink draws with
  /// their tf rate and exaggeration from the next output on.
  void apply(const RuntimeSettings& settings);

  const OutputSettings& settings() const { return settings_; }

 protected:
  virtual void emitStiffness(const drivetrain_stiffness::Stiffness& msg) = 0;
  virtual void emitTransmissionError(const drivetrain_stiffness::TransmissionError& msg) = 0;
  virtual void emitSpectrum(const drivetrain_stiffness::SpectralPeaks& msg) = 0;
  virtual void emitResonance(const drivetrain_stiffness::Resonance& msg) = 0;
  virtual void emitMeasuredTe(const drivetrain_stiffness::MeasuredTe& msg) = 0;
  virtual void emitCalibration(const drivetrain_stiffness::Calibration& msg) = 0;
  virtual void emitMeshPeriodStats(const drivetrain_stiffness::MeshPeriodStats& msg) = 0;
  virtual void emitModalIdentification(const drivetrain_stiffness::ModalIdentification& msg) = 0;
  virtual void emitTransforms(const std::vector<geometry_msgs::TransformStamped>& transforms) = 0;
  virtual void emitMarkers(const visualization_msgs::MarkerArray& markers) = 0;

 private:
  OutputSettings settings_;
  double tf_rate_ = 0.0;  ///< [Hz] the run-time settings' (~tf_rate)
  double exaggeration_ =
      1.0;  ///< the run-time settings' (~exaggeration), taken up at the next tf output
  RigVisualizer visualizer_;
  std::optional<Stamp> last_tf_;
  drivetrain_stiffness::Stiffness
      stiffness_msg_;  ///< refilled per update (publish serializes it at once)
  // header.seq of the stiffness, transmission_error, measured_te, calibration and mesh_period_stats
  // messages, numbered from 0: what a bag written by drivetrain_replay carries (on the live graph
  // roscpp writes its own per-publication count, the same numbers while a subscriber listens): a
  // reader sees from the gaps what it lost.
  std::uint32_t stiffness_seq_ = 0, te_seq_ = 0, measured_te_seq_ = 0, calibration_seq_ = 0,
                mesh_period_seq_ = 0, modal_seq_ = 0;
};

}  // namespace drivetrain_stiffness

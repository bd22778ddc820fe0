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
  /// The pipeline supplies the rig geometry, the nominal pinion angle, the last resonance and the
  /// run-time settings (exaggeration, tf rate).
  MessageSink(const RigPipeline& pipeline, const OutputSettings& settings);

  void stiffness(Stamp stamp, const StiffnessEstimate& estimate) override;
  void transmissionError(Stamp stamp, const DynamicsSample& sample) override;
  void spectrum(Stamp stamp, const SlidingSpectrum& spectrum) override;
  void resonance(Stamp stamp, const ResonanceEstimate& estimate) override;
  void measuredTe(Stamp stamp, const MeasuredTeSample& sample) override;
  void calibration(Stamp stamp, const CalibrationEstimate& estimate) override;
  void meshPeriod(Stamp stamp, const MeshPeriodStatistics& stats) override;

  const OutputSettings& settings() const { return settings_; }

 private:
  /// The calibration's stiffness bands at this estimate's torque, or the drawing's model (zero width).
  CalibrationBands stiffnessBands(const StiffnessEstimate& estimate) const;

 protected:
  virtual void emitStiffness(const drivetrain_stiffness::Stiffness& msg) = 0;
  virtual void emitTransmissionError(const drivetrain_stiffness::TransmissionError& msg) = 0;
  virtual void emitSpectrum(const drivetrain_stiffness::SpectralPeaks& msg) = 0;
  virtual void emitResonance(const drivetrain_stiffness::Resonance& msg) = 0;
  virtual void emitMeasuredTe(const drivetrain_stiffness::MeasuredTe& msg) = 0;
  virtual void emitCalibration(const drivetrain_stiffness::Calibration& msg) = 0;
  virtual void emitMeshPeriodStats(const drivetrain_stiffness::MeshPeriodStats& msg) = 0;
  virtual void emitTransforms(const std::vector<geometry_msgs::TransformStamped>& transforms) = 0;
  virtual void emitMarkers(const visualization_msgs::MarkerArray& markers) = 0;

 private:
  const RigPipeline& pipeline_;
  OutputSettings settings_;
  RigVisualizer visualizer_;
  std::optional<Stamp> last_tf_;
  drivetrain_stiffness::Stiffness stiffness_msg_;  ///< refilled per update (publish serializes it at once)
  // header.seq of the stiffness, transmission_error, measured_te, calibration and mesh_period_stats messages, numbered
  // from 0: what a bag written by drivetrain_replay carries (on the live graph roscpp writes its own
  // per-publication count, the same numbers while a subscriber listens): a reader sees from the
  // gaps what it lost.
  std::uint32_t stiffness_seq_ = 0, te_seq_ = 0, measured_te_seq_ = 0, calibration_seq_ = 0, mesh_period_seq_ = 0;
};

}  // namespace drivetrain_stiffness

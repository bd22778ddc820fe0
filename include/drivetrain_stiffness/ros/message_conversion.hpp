// Conversions between ROS messages and the ROS-free pipeline, shared by the node, the nodelet and
// the bag replay tool: the input messages as the pipeline takes them, so that all three feed it
// the same values, and its outputs as this package's messages, so that all three publish exactly
// the same fields.
#pragma once

#include <ros/time.h>

#include "drivetrain_stiffness/Calibration.h"
#include "drivetrain_stiffness/MeasuredTe.h"
#include "drivetrain_stiffness/MeshPeriodStats.h"
#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/Resonance.h"
#include "drivetrain_stiffness/SpectralPeaks.h"
#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include <geometry_msgs/WrenchStamped.h>
#include <sensor_msgs/JointState.h>

#include <string_view>

namespace drivetrain_stiffness {

/// Refuses (InvalidInput) a stamp that ros::Time cannot hold instead of narrowing it to uint32:
/// the pipeline never makes one (the stamp-range rule), so this only guards other callers.
ros::Time toRosTime(Stamp s);
inline Stamp fromRosTime(const ros::Time& t) { return Stamp::fromSecNsec(t.sec, t.nsec); }

/// The encoders' joint names in joint_states (~pinion_joint, ~gear_joint).
struct JointNames {
  std::string pinion = "pinion", gear = "gear";
};
/// The reading of a JointState message: the pinion's position (required), its velocity and the
/// gear's position when present. Without a pinion position: nullopt and `why` says what is missing
/// (the pipeline counts it, RigPipeline::motionRefused).
std::optional<MotionInput> toMotionInput(const sensor_msgs::JointState& msg,
                                         const JointNames& names, std::string& why);
/// The message's joint names for a refusal ("joints 'motor', 'output'"; printable, the first few).
std::string jointNamesOf(const sensor_msgs::JointState& msg);

/// A torque message as RigPipeline::torque takes it: its stamp, the torque about the shaft axis
/// (wrench.torque.z; the other components are not read) and its origin (the publisher's caller id,
/// header.seq, header.frame_id). The origin's views point into `msg` and `publisher`: use the
/// result while both live (node and replay pass it straight to the pipeline).
struct TorqueInput {
  Stamp stamp;
  double torque = 0.0;
  InputOrigin origin;
};
TorqueInput toTorqueInput(const geometry_msgs::WrenchStamped& msg, std::string_view publisher);

/// A Preload message's settings into the caller's `out`, as the pipeline takes them (node and
/// replay). `out` is resized and its elements assigned in place (names into their strings), so a
/// buffer kept by the caller allocates nothing once it has held a message as large, names as long.
void toPreloadSettings(const drivetrain_stiffness::Preload& msg, std::vector<PreloadSetting>& out);

/// The stiffness message into `out`, reusing its bearings array and strings: the sinks keep one
/// message and refill it for every update (1 kHz and more) instead of allocating one per update.
void fillStiffnessMsg(Stamp stamp, const std::string& frame_id, const StiffnessEstimate& estimate,
                      drivetrain_stiffness::Stiffness& out);
drivetrain_stiffness::TransmissionError toTransmissionErrorMsg(Stamp stamp,
                                                               const std::string& frame_id,
                                                               const DynamicsSample& s);
drivetrain_stiffness::SpectralPeaks toSpectralPeaksMsg(Stamp stamp, const std::string& frame_id,
                                                       const SpectrumPeaks& peaks);
drivetrain_stiffness::Resonance toResonanceMsg(Stamp stamp, const std::string& frame_id,
                                               const ResonanceEstimate& r);
/// The calibrated stiffness and natural frequencies with their 95 % bounds into the stiffness and
/// resonance messages (docs/calibration.md section 4); refuses a non-finite number, naming it.
void fillStiffnessBands(const CalibrationBands& bands, drivetrain_stiffness::Stiffness& out);
void fillResonanceBands(const CalibrationBands& bands, drivetrain_stiffness::Resonance& out);
/// The calibration after a window (the calibration rule) and one reading's measured TE. Both refuse
/// (InvalidInput naming the field) a non-finite number instead of publishing it; the pipeline
/// counts that in calibration_errors.
drivetrain_stiffness::Calibration toCalibrationMsg(Stamp stamp, const std::string& frame_id,
                                                   const CalibrationEstimate& e);
drivetrain_stiffness::MeasuredTe toMeasuredTeMsg(Stamp stamp, const std::string& frame_id,
                                                 const MeasuredTeSample& s);
/// One block of whole mesh periods (MeshPeriodStatistics); refuses a non-finite number as the two
/// above.
drivetrain_stiffness::MeshPeriodStats toMeshPeriodStatsMsg(Stamp stamp, const std::string& frame_id,
                                                           const MeshPeriodStatistics& s);
/// The calibration's state in words, for /diagnostics and the replay's summary: the last window's
/// outcome, or why the pipeline runs without a calibration (no calibration block, ~calibrate false,
/// no dynamics block).
std::string calibrationStatus(const RigPipeline& pipeline);
/// The parameters whose posterior std fell below half the prior's, by calibrationName, joined with
/// ", "; "none" if none.
std::string identifiedParameters(const CalibrationEstimate& estimate);

}  // namespace drivetrain_stiffness

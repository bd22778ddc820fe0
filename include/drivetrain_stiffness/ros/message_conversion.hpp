// Conversions between ROS messages and the ROS-free pipeline, one set for the node, the nodelet and
// drivetrain_replay, so all three take and publish the same values.
#pragma once

#include <ros/time.h>

#include "drivetrain_stiffness/Calibration.h"
#include "drivetrain_stiffness/MeasuredTe.h"
#include "drivetrain_stiffness/MeshPeriodStats.h"
#include "drivetrain_stiffness/ModalIdentification.h"
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

/// Throws InvalidInput for a stamp ros::Time cannot hold.
ros::Time toRosTime(Stamp s);
inline Stamp fromRosTime(const ros::Time& t) { return Stamp::fromSecNsec(t.sec, t.nsec); }

/// The encoders' joint names in joint_states (~pinion_joint, ~gear_joint).
struct JointNames {
  std::string pinion = "pinion", gear = "gear";
};
/// A JointState's reading; without the pinion's position nullopt, and `why` says what is missing.
std::optional<MotionInput> toMotionInput(const sensor_msgs::JointState& msg,
                                         const JointNames& names, std::string& why);
/// The message's first joint names, printable, for a refusal.
std::string jointNamesOf(const sensor_msgs::JointState& msg);

/// A torque message as RigPipeline::torque takes it (wrench.torque.z [N*m]); the origin's views
/// point into `msg` and `publisher`.
struct TorqueInput {
  Stamp stamp;
  double torque = 0.0;
  InputOrigin origin;
};
TorqueInput toTorqueInput(const geometry_msgs::WrenchStamped& msg, std::string_view publisher);

/// A Preload message's settings into `out`, assigned in place (allocation-free once it has held a
/// message as large).
void toPreloadSettings(const drivetrain_stiffness::Preload& msg, std::vector<PreloadSetting>& out);

/// The stiffness message into `out`, reusing its storage.
void fillStiffnessMsg(Stamp stamp, const std::string& frame_id, const StiffnessEstimate& estimate,
                      drivetrain_stiffness::Stiffness& out);
drivetrain_stiffness::TransmissionError toTransmissionErrorMsg(Stamp stamp,
                                                               const std::string& frame_id,
                                                               const DynamicsSample& s);
drivetrain_stiffness::SpectralPeaks toSpectralPeaksMsg(Stamp stamp, const std::string& frame_id,
                                                       const SpectrumPeaks& peaks);
drivetrain_stiffness::Resonance toResonanceMsg(Stamp stamp, const std::string& frame_id,
                                               const ResonanceEstimate& r);
/// The 95 % bands into the stiffness and resonance messages (docs/calibration.md section 4).
/// Throws InvalidInput naming a non-finite number.
void fillStiffnessBands(const CalibrationBands& bands, drivetrain_stiffness::Stiffness& out);
void fillResonanceBands(const CalibrationBands& bands, drivetrain_stiffness::Resonance& out);
/// The calibration after a window and one reading's measured TE. Throw InvalidInput naming a
/// non-finite field.
drivetrain_stiffness::Calibration toCalibrationMsg(Stamp stamp, const std::string& frame_id,
                                                   const CalibrationEstimate& e);
drivetrain_stiffness::MeasuredTe toMeasuredTeMsg(Stamp stamp, const std::string& frame_id,
                                                 const MeasuredTeSample& s);
/// One block of whole mesh periods. Throws InvalidInput naming a non-finite field.
drivetrain_stiffness::MeshPeriodStats toMeshPeriodStatsMsg(Stamp stamp, const std::string& frame_id,
                                                           const MeshPeriodStatistics& s);
/// One record's modal identification; a standard deviation not computed is 0. Throws
/// InvalidInput naming a non-finite field.
drivetrain_stiffness::ModalIdentification toModalIdentificationMsg(Stamp stamp,
                                                                   const std::string& frame_id,
                                                                   const ModalReport& r);
/// The calibration's state in words: the last window's outcome, or why there is none.
std::string calibrationStatus(const RigPipeline& pipeline);
/// The identified parameters' names joined with ", "; "none" if none.
std::string identifiedParameters(const CalibrationEstimate& estimate);

}  // namespace drivetrain_stiffness

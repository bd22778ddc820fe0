// The node's private parameters, read the same way from the ROS parameter server (the node and
// nodelet) and from the same YAML file loaded by hand (drivetrain_replay --params), so both run
// the pipeline with identical settings. `get(name, fallback)` returns the value or the fallback
// and throws InvalidInput naming the parameter when it has the wrong type.
#pragma once

#include <map>
#include <string>
#include <utility>

#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "drivetrain_stiffness/ros/message_sink.hpp"

namespace drivetrain_stiffness {

template <typename Get>
PipelineOptions readPipelineOptions(const Get& get, const RigConfig& rig) {
  PipelineOptions o;
  o.limits.max_abs_torque = get("max_abs_torque", o.limits.max_abs_torque);
  o.limits.max_preload = get("max_preload", o.limits.max_preload);
  o.limits.max_interference = get("max_interference", o.limits.max_interference);
  o.limits.load_tolerance = get("bearing_load_tolerance", o.limits.load_tolerance);
  o.dynamics = get("dynamics", rig.dynamics.present);
  o.output_rate = get("output_rate", o.output_rate);
  o.max_gap = get("max_gap", o.max_gap);
  o.stamp_jump_back = get("stamp_jump_back", o.stamp_jump_back);
  o.clock_jump_back = get("clock_jump_back", o.clock_jump_back);
  o.resonance_threshold = get("resonance_threshold", o.resonance_threshold);
  o.spectrum_window = get("spectrum_window", o.spectrum_window);
  o.spectrum_hop = get("spectrum_hop", o.spectrum_hop);
  // One speed for both mesh phases (stiffness and dynamics): the dynamics block's, unless
  // overridden.
  o.pinion_speed_rpm =
      get("pinion_speed_rpm", rig.dynamics.present ? rig.dynamics.speed_rpm : 1000.0);
  // The torque sensor's frame: torque.z about the pinion axis (right-hand rule, REP 103). A torque
  // in another frame has another sign convention, so it is refused unless the user names the frame.
  o.torque_frame = get("torque_frame", std::string("pinion"));
  // joint_states (the rig's encoders): where a drive pair enters contact at pinion angle 0, how
  // long a silent encoder stream is trusted, and how far the gear may run off the tooth ratio.
  o.mesh_phase_offset = get("mesh_phase_offset", o.mesh_phase_offset);
  o.motion_timeout = get("motion_timeout", o.motion_timeout);
  o.gear_ratio_tolerance = get("gear_ratio_tolerance", o.gear_ratio_tolerance);
  o.motion_slices = get("motion_slices", o.motion_slices);
  // The calibration rule: calibrate against the encoders' TE when the gearbox has a calibration
  // block.
  o.calibrate = get("calibrate", o.calibrate);
  // Accelerometers (docs/vibration.md "Input"): channels named otherwise than a bearing support.
  o.vibration_channels =
      parseVibrationAliases(get("vibration_channels", std::map<std::string, std::string>{}));
  o.vibration_record = get("vibration_record", o.vibration_record);
  o.modal_identification = get("modal_identification", o.modal_identification);
  o.modal_max_order = get("modal_max_order", o.modal_max_order);
  o.modal_block_rows = get("modal_block_rows", o.modal_block_rows);
  o.modal_skipped_lags = get("modal_skipped_lags", o.modal_skipped_lags);
  o.modal_band = get("modal_band", o.modal_band);
  try {
    o.validate();
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string("parameter ~") + e.what());
  }
  return o;
}

/// The run-time settings at start-up: the gearbox's damping, the rest from the parameters.
template <typename Get>
RuntimeSettings readRuntimeSettings(const Get& get, const RigConfig& rig) {
  RuntimeSettings s = RuntimeSettings::forRig(rig);
  s.fidelity = parseFidelity("~fidelity", get("fidelity", std::string(toString(s.fidelity))));
  s.stiffness_rate = get("stiffness_rate", s.stiffness_rate);
  s.exaggeration = get("exaggeration", s.exaggeration);
  s.tf_rate = get("tf_rate", s.tf_rate);
  try {
    s.validate();
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string("parameter ~") + e.what());
  }
  return s;
}

/// ~pinion_joint, ~gear_joint: the joint names of the two encoders in joint_states.
template <typename Get>
JointNames readJointNames(const Get& get) {
  JointNames j;
  j.pinion = get("pinion_joint", j.pinion);
  j.gear = get("gear_joint", j.gear);
  if (j.pinion.empty() || j.gear.empty() || j.pinion == j.gear) {
    throw InvalidInput("parameters ~pinion_joint = '" + j.pinion + "', ~gear_joint = '" + j.gear +
                       "': two different, non-empty joint names");
  }
  return j;
}

template <typename Get>
OutputSettings readOutputSettings(const Get& get) {
  OutputSettings s;
  s.frames.rig = get("rig_frame", s.frames.rig);
  s.frames.pinion = get("pinion_frame", s.frames.pinion);
  s.frames.gear = get("gear_frame", s.frames.gear);
  const std::pair<const char*, const std::string*> frames[] = {{"rig_frame", &s.frames.rig},
                                                               {"pinion_frame", &s.frames.pinion},
                                                               {"gear_frame", &s.frames.gear}};
  for (const auto& [name, f] : frames) {
    if (f->empty() || f->front() == '/') {
      throw InvalidInput(std::string("parameter ~") + name + " = '" + *f +
                         "': must be a non-empty frame id without a leading '/'");
    }
  }
  return s;
}

}  // namespace drivetrain_stiffness

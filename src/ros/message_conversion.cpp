#include "drivetrain_stiffness/ros/message_conversion.hpp"

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

ros::Time toRosTime(Stamp s) {
  if (!s.inRosRange()) {
    throw InvalidInput("stamp = " + formatValue(s.toSec()) + " s: outside ROS time [0, 4294967295.999999999] s (1970 to 2106)");
  }
  return ros::Time(static_cast<std::uint32_t>(s.sec()), static_cast<std::uint32_t>(s.nsec()));
}

std::vector<PreloadSetting> toPreloadSettings(const drivetrain_stiffness::Preload& msg) {
  std::vector<PreloadSetting> settings;
  settings.reserve(msg.bearings.size());
  for (const auto& b : msg.bearings) {
    settings.push_back({b.name, b.axial_preload, b.radial_preload, b.inner_interference, b.outer_interference});
  }
  return settings;
}

void fillStiffnessMsg(Stamp stamp, const std::string& frame_id, const StiffnessEstimate& estimate,
                      drivetrain_stiffness::Stiffness& out) {
  out.header.stamp = toRosTime(stamp);
  out.header.frame_id = frame_id;
  out.torque = estimate.torque;
  out.mesh_force = estimate.mesh_force;
  out.mesh_phase = estimate.mesh.phase;
  out.mesh_stiffness = estimate.mesh.current.composite;
  out.mesh_stiffness_mean = estimate.mesh.mean;
  out.mesh_stiffness_drive = estimate.mesh.current.k1;
  out.mesh_stiffness_back = estimate.mesh.current.k2;
  out.drive_flank_loaded = estimate.mesh.current.contact != FlankContact::kBackOnly;
  out.back_flank_loaded = estimate.mesh.current.contact != FlankContact::kDriveOnly;
  out.bearings.resize(estimate.supports.size());
  for (std::size_t k = 0; k < estimate.supports.size(); ++k) {
    const SupportEstimate& s = estimate.supports[k];
    drivetrain_stiffness::BearingStiffness& b = out.bearings[k];
    const BearingSolution& sol = s.solution;
    b.name = s.name;
    b.radial_stiffness = sol.radialStiffness();
    b.axial_stiffness = sol.axialStiffness();
    b.tilt_stiffness = sol.tiltStiffness();
    b.radial_load = s.radial_load;
    b.axial_load = s.axial_load;
    b.radial_displacement = sol.displacement[kUx];
    b.axial_displacement = sol.displacement[kUz];
    b.max_contact_pressure = sol.max_contact_pressure;
    b.balls_in_contact = static_cast<std::uint32_t>(sol.balls_in_contact);
    b.iterations = static_cast<std::uint32_t>(sol.iterations);
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) b.stiffness_matrix[5 * i + j] = sol.stiffness(i, j);
  }
  // Flat copies of the first two supports (pinion side, gear side), for rqt_plot and PlotJuggler.
  out.radial_stiffness_0 = estimate.supports.empty() ? 0.0 : out.bearings[0].radial_stiffness;
  out.radial_stiffness_1 = estimate.supports.size() > 1 ? out.bearings[1].radial_stiffness : 0.0;
}

drivetrain_stiffness::TransmissionError toTransmissionErrorMsg(Stamp stamp, const std::string& frame_id, const DynamicsSample& s) {
  drivetrain_stiffness::TransmissionError m;
  m.header.stamp = toRosTime(stamp);
  m.header.frame_id = frame_id;
  m.dynamic_te = s.dynamic_te;
  m.static_te = s.static_te;
  m.x_p = s.state[0];
  m.x_g = s.state[1];
  m.x = s.state[2];
  m.mesh_force = s.mesh_force;
  m.mesh_phase = s.phase;
  m.torque = s.torque;
  m.drive_flank_loaded = s.drive_flank_loaded;
  m.back_flank_loaded = s.back_flank_loaded;
  return m;
}

drivetrain_stiffness::SpectralPeaks toSpectralPeaksMsg(Stamp stamp, const std::string& frame_id, const SlidingSpectrum& spectrum) {
  drivetrain_stiffness::SpectralPeaks peaks;
  peaks.header.stamp = toRosTime(stamp);
  peaks.header.frame_id = frame_id;
  for (const SpectralPeak& p : spectrum.peaks()) {
    peaks.frequencies_hz.push_back(p.frequency);
    peaks.amplitudes.push_back(p.amplitude);
  }
  // Flat copies of the strongest peak, for plotting tools that do not index arrays.
  if (!spectrum.peaks().empty()) {
    peaks.peak_frequency_hz = spectrum.peaks().front().frequency;
    peaks.peak_amplitude = spectrum.peaks().front().amplitude;
  }
  peaks.window_s = spectrum.windowSeconds();
  peaks.resolution_hz = spectrum.resolution();
  return peaks;
}

drivetrain_stiffness::Resonance toResonanceMsg(Stamp stamp, const std::string& frame_id, const ResonanceEstimate& r) {
  drivetrain_stiffness::Resonance msg;
  msg.header.stamp = toRosTime(stamp);
  msg.header.frame_id = frame_id;
  for (const Mode& m : r.modes) {
    msg.frequencies_hz.push_back(m.natural_frequency);
    msg.damped_frequencies_hz.push_back(m.damped_frequency);
    msg.damping_ratios.push_back(m.damping_ratio);
    msg.dominant_coordinate.push_back(m.dominant);
  }
  msg.f1_hz = r.modes[0].natural_frequency;
  msg.f2_hz = r.modes[1].natural_frequency;
  msg.f3_hz = r.modes[2].natural_frequency;
  msg.floquet_valid = r.floquet_valid;
  msg.floquet_margin = r.floquet_margin;
  msg.source = "modal: bearing model at this load, mean composite mesh stiffness of the flank state; "
               "Floquet: exact monodromy of the mesh period";
  return msg;
}

}  // namespace drivetrain_stiffness

namespace drivetrain_stiffness {

std::optional<MotionInput> toMotionInput(const sensor_msgs::JointState& msg, const JointNames& names, std::string& why) {
  // sensor_msgs/JointState: name[i] goes with position[i], velocity[i], effort[i]; velocity and
  // effort may be empty (not measured).
  auto index = [&](const std::string& joint) -> long {
    for (std::size_t i = 0; i < msg.name.size(); ++i) {
      if (msg.name[i] == joint) return static_cast<long>(i);
    }
    return -1;
  };
  const long p = index(names.pinion);
  if (p < 0 || static_cast<std::size_t>(p) >= msg.position.size()) {
    why = p < 0 ? "no joint named '" + names.pinion + "' (~pinion_joint)"
                : "joint '" + names.pinion + "' has no position (" + std::to_string(msg.position.size()) + " positions for " +
                      std::to_string(msg.name.size()) + " names)";
    return std::nullopt;
  }
  MotionInput m;
  m.pinion_angle = msg.position[static_cast<std::size_t>(p)];
  if (static_cast<std::size_t>(p) < msg.velocity.size()) m.pinion_velocity = msg.velocity[static_cast<std::size_t>(p)];
  const long g = index(names.gear);
  if (g >= 0 && static_cast<std::size_t>(g) < msg.position.size()) m.gear_angle = msg.position[static_cast<std::size_t>(g)];
  return m;
}

}  // namespace drivetrain_stiffness

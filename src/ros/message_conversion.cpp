#include "drivetrain_stiffness/ros/message_conversion.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

ros::Time toRosTime(Stamp s) {
  if (!s.inRosRange()) {
    throw InvalidInput("stamp = " + formatValue(s.toSec()) +
                       " s: outside ROS time [0, 4294967295.999999999] s (1970 to 2106)");
  }
  return ros::Time(static_cast<std::uint32_t>(s.sec()), static_cast<std::uint32_t>(s.nsec()));
}

TorqueInput toTorqueInput(const geometry_msgs::WrenchStamped& msg, std::string_view publisher) {
  return {fromRosTime(msg.header.stamp),
          msg.wrench.torque.z,
          {publisher, msg.header.seq, msg.header.frame_id}};
}

void toPreloadSettings(const drivetrain_stiffness::Preload& msg, std::vector<PreloadSetting>& out) {
  out.resize(msg.bearings.size());  // keeps the capacity and the elements' strings
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto& b = msg.bearings[i];
    PreloadSetting& s = out[i];
    s.name = b.name;  // std::string assignment: reuses the element's buffer
    s.axial_preload = b.axial_preload;
    s.radial_preload = b.radial_preload;
    s.inner_interference = b.inner_interference;
    s.outer_interference = b.outer_interference;
  }
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

drivetrain_stiffness::TransmissionError toTransmissionErrorMsg(Stamp stamp,
                                                               const std::string& frame_id,
                                                               const DynamicsSample& s) {
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

drivetrain_stiffness::SpectralPeaks toSpectralPeaksMsg(Stamp stamp, const std::string& frame_id,
                                                       const SpectrumPeaks& in) {
  drivetrain_stiffness::SpectralPeaks peaks;
  peaks.header.stamp = toRosTime(stamp);
  peaks.header.frame_id = frame_id;
  for (std::size_t i = 0; i < in.count; ++i) {
    peaks.frequencies_hz.push_back(in.peaks[i].frequency);
    peaks.amplitudes.push_back(in.peaks[i].amplitude);
  }
  // Flat copies of the strongest peak, for plotting tools that do not index arrays.
  if (in.count > 0) {
    peaks.peak_frequency_hz = in.peaks[0].frequency;
    peaks.peak_amplitude = in.peaks[0].amplitude;
  }
  peaks.window_s = in.window_seconds;
  peaks.resolution_hz = in.resolution;
  return peaks;
}

drivetrain_stiffness::Resonance toResonanceMsg(Stamp stamp, const std::string& frame_id,
                                               const ResonanceEstimate& r) {
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
  msg.source =
      "modal: bearing model at this load, mean composite mesh stiffness of the flank state; "
      "Floquet: exact monodromy of the mesh period";
  return msg;
}

namespace {

/// Never a NaN on a topic: a non-finite number is refused with the message field named.
double finite(const char* msg, const char* field, double value) {
  if (!std::isfinite(value))
    throw InvalidInput(std::string(msg) + "." + field + " = " + formatValue(value) +
                       ": not finite, not published");
  return value;
}

}  // namespace

// The message has flat fields for the five parameters and the three features: a change of either
// vector must come with a change of the message.
static_assert(kCalibrationSize == 5 && kMeshScale == 0 && kPinionBearingScale == 1 &&
                  kGearBearingScale == 2 && kPreloadTorque == 3 && kTeOffset == 4,
              "Calibration.msg holds exactly these parameters");
static_assert(kFeatureSize == 3, "Calibration.msg holds the mean TE and two mesh harmonics");

void fillStiffnessBands(const CalibrationBands& b, drivetrain_stiffness::Stiffness& m) {
  auto f = [](const char* field, double value) { return finite("stiffness", field, value); };
  m.calibrated = b.calibrated;
  m.mesh_stiffness_mean_calibrated = f("mesh_stiffness_mean_calibrated", b.mesh_stiffness);
  m.mesh_stiffness_mean_low = f("mesh_stiffness_mean_low", b.mesh_stiffness_low);
  m.mesh_stiffness_mean_high = f("mesh_stiffness_mean_high", b.mesh_stiffness_high);
  m.pinion_bearing_stiffness_calibrated =
      f("pinion_bearing_stiffness_calibrated", b.bearing_stiffness[0]);
  m.pinion_bearing_stiffness_low = f("pinion_bearing_stiffness_low", b.bearing_stiffness_low[0]);
  m.pinion_bearing_stiffness_high = f("pinion_bearing_stiffness_high", b.bearing_stiffness_high[0]);
  m.gear_bearing_stiffness_calibrated =
      f("gear_bearing_stiffness_calibrated", b.bearing_stiffness[1]);
  m.gear_bearing_stiffness_low = f("gear_bearing_stiffness_low", b.bearing_stiffness_low[1]);
  m.gear_bearing_stiffness_high = f("gear_bearing_stiffness_high", b.bearing_stiffness_high[1]);
}

void fillResonanceBands(const CalibrationBands& b, drivetrain_stiffness::Resonance& m) {
  auto f = [](const char* field, double value) { return finite("resonance", field, value); };
  m.calibrated = b.calibrated;
  m.f1_hz_calibrated = f("f1_hz_calibrated", b.natural_frequency[0]);
  m.f1_hz_low = f("f1_hz_low", b.natural_frequency_low[0]);
  m.f1_hz_high = f("f1_hz_high", b.natural_frequency_high[0]);
  m.f2_hz_calibrated = f("f2_hz_calibrated", b.natural_frequency[1]);
  m.f2_hz_low = f("f2_hz_low", b.natural_frequency_low[1]);
  m.f2_hz_high = f("f2_hz_high", b.natural_frequency_high[1]);
  m.f3_hz_calibrated = f("f3_hz_calibrated", b.natural_frequency[2]);
  m.f3_hz_low = f("f3_hz_low", b.natural_frequency_low[2]);
  m.f3_hz_high = f("f3_hz_high", b.natural_frequency_high[2]);
}

drivetrain_stiffness::Calibration toCalibrationMsg(Stamp stamp, const std::string& frame_id,
                                                   const CalibrationEstimate& e) {
  auto f = [](const char* field, double value) { return finite("calibration", field, value); };
  drivetrain_stiffness::Calibration m;
  m.header.stamp = toRosTime(stamp);
  m.header.frame_id = frame_id;
  // The parameters in CalibrationIndex order; the field names are calibrationName(i) (and _std,
  // _identified), which the replay's CSV columns and --calibrate's YAML keys use as well.
  m.mesh_stiffness_scale = f("mesh_stiffness_scale", e.value[kMeshScale]);
  m.mesh_stiffness_scale_std = f("mesh_stiffness_scale_std", e.std[kMeshScale]);
  m.pinion_bearing_scale = f("pinion_bearing_scale", e.value[kPinionBearingScale]);
  m.pinion_bearing_scale_std = f("pinion_bearing_scale_std", e.std[kPinionBearingScale]);
  m.gear_bearing_scale = f("gear_bearing_scale", e.value[kGearBearingScale]);
  m.gear_bearing_scale_std = f("gear_bearing_scale_std", e.std[kGearBearingScale]);
  m.preload_torque = f("preload_torque", e.value[kPreloadTorque]);
  m.preload_torque_std = f("preload_torque_std", e.std[kPreloadTorque]);
  m.te_offset = f("te_offset", e.value[kTeOffset]);
  m.te_offset_std = f("te_offset_std", e.std[kTeOffset]);
  m.mesh_stiffness_scale_identified = e.identified[kMeshScale];
  m.pinion_bearing_scale_identified = e.identified[kPinionBearingScale];
  m.gear_bearing_scale_identified = e.identified[kGearBearingScale];
  m.preload_torque_identified = e.identified[kPreloadTorque];
  m.te_offset_identified = e.identified[kTeOffset];
  m.nis = f("nis", e.nis);
  m.excited = e.excited;
  m.baseline = e.baseline;
  m.outcome = toString(e.outcome);
  m.windows = e.windows;
  m.baseline_windows = e.baseline_windows;
  m.updates = e.updates;
  m.gated = e.gated;
  m.not_excited = e.not_excited;
  m.modal_updates = e.modal_updates;
  m.modal_gated = e.modal_gated;
  m.modal_nis = f("modal_nis", e.modal_nis);
  m.window_torque = f("window_torque", e.window_torque);
  m.window_speed = f("window_speed", e.window_speed);
  m.series_compliance = f("series_compliance", e.series_compliance);
  m.series_compliance_std = f("series_compliance_std", e.series_compliance_std);
  m.mesh_stiffness = f("mesh_stiffness", e.mesh_stiffness);
  m.mesh_stiffness_low = f("mesh_stiffness_low", e.mesh_stiffness_low);
  m.mesh_stiffness_high = f("mesh_stiffness_high", e.mesh_stiffness_high);
  m.pinion_bearing_stiffness = f("pinion_bearing_stiffness", e.bearing_stiffness[0]);
  m.pinion_bearing_stiffness_low = f("pinion_bearing_stiffness_low", e.bearing_stiffness_low[0]);
  m.pinion_bearing_stiffness_high = f("pinion_bearing_stiffness_high", e.bearing_stiffness_high[0]);
  m.gear_bearing_stiffness = f("gear_bearing_stiffness", e.bearing_stiffness[1]);
  m.gear_bearing_stiffness_low = f("gear_bearing_stiffness_low", e.bearing_stiffness_low[1]);
  m.gear_bearing_stiffness_high = f("gear_bearing_stiffness_high", e.bearing_stiffness_high[1]);
  m.natural_frequency_1 = f("natural_frequency_1", e.natural_frequency[0]);
  m.natural_frequency_1_low = f("natural_frequency_1_low", e.natural_frequency_low[0]);
  m.natural_frequency_1_high = f("natural_frequency_1_high", e.natural_frequency_high[0]);
  m.natural_frequency_2 = f("natural_frequency_2", e.natural_frequency[1]);
  m.natural_frequency_2_low = f("natural_frequency_2_low", e.natural_frequency_low[1]);
  m.natural_frequency_2_high = f("natural_frequency_2_high", e.natural_frequency_high[1]);
  m.natural_frequency_3 = f("natural_frequency_3", e.natural_frequency[2]);
  m.natural_frequency_3_low = f("natural_frequency_3_low", e.natural_frequency_low[2]);
  m.natural_frequency_3_high = f("natural_frequency_3_high", e.natural_frequency_high[2]);
  m.knee_torque = f("knee_torque", e.knee_torque);
  // FeatureVector: the mean TE, then the mesh harmonics 1 and 2.
  m.measured_mean_te = f("measured_mean_te", e.measured[0]);
  m.predicted_mean_te = f("predicted_mean_te", e.predicted[0]);
  m.measured_mesh_harmonic_1 = f("measured_mesh_harmonic_1", e.measured[1]);
  m.predicted_mesh_harmonic_1 = f("predicted_mesh_harmonic_1", e.predicted[1]);
  m.measured_mesh_harmonic_2 = f("measured_mesh_harmonic_2", e.measured[2]);
  m.predicted_mesh_harmonic_2 = f("predicted_mesh_harmonic_2", e.predicted[2]);
  return m;
}

drivetrain_stiffness::MeasuredTe toMeasuredTeMsg(Stamp stamp, const std::string& frame_id,
                                                 const MeasuredTeSample& s) {
  auto f = [](const char* field, double value) { return finite("measured_te", field, value); };
  drivetrain_stiffness::MeasuredTe m;
  m.header.stamp = toRosTime(stamp);
  m.header.frame_id = frame_id;
  m.te = f("te", s.te);
  m.predicted = f("predicted", s.predicted);
  m.residual = f("residual", s.residual);
  m.torque = f("torque", s.torque);
  m.mesh_phase = f("mesh_phase", s.phase);
  return m;
}

drivetrain_stiffness::MeshPeriodStats toMeshPeriodStatsMsg(Stamp stamp, const std::string& frame_id,
                                                           const MeshPeriodStatistics& s) {
  auto f = [](const char* field, double value) {
    return finite("mesh_period_stats", field, value);
  };
  drivetrain_stiffness::MeshPeriodStats m;
  m.header.stamp = toRosTime(stamp);
  m.header.frame_id = frame_id;
  m.te_mean = f("te_mean", s.te_mean);
  m.te_rms = f("te_rms", s.te_rms);
  m.te_peak_to_peak = f("te_peak_to_peak", s.te_peak_to_peak);
  m.mesh_force_mean = f("mesh_force_mean", s.mesh_force_mean);
  m.mesh_force_rms = f("mesh_force_rms", s.mesh_force_rms);
  m.mesh_force_peak_to_peak = f("mesh_force_peak_to_peak", s.mesh_force_peak_to_peak);
  m.mesh_frequency = f("mesh_frequency", s.mesh_frequency);
  m.torque = f("torque", s.torque);
  m.periods = s.periods;
  m.samples = s.samples;
  m.duration = f("duration", s.duration);
  return m;
}

namespace {

/// A standard deviation for a message: 0 when not computed (NaN).
double stdOrZero(double s) { return std::isnan(s) ? 0.0 : s; }

drivetrain_stiffness::IdentifiedMode toIdentifiedModeMsg(const ModalReport& r, std::size_t i) {
  auto f = [](const char* field, double value) {
    return finite("modal_identification.modes", field, value);
  };
  const modal::IdentifiedMode& m = r.modes[i];
  drivetrain_stiffness::IdentifiedMode out;
  out.frequency = f("frequency", m.frequency);
  out.frequency_std = f("frequency_std", stdOrZero(m.frequency_std));
  out.damping = f("damping", m.damping);
  out.damping_std = f("damping_std", stdOrZero(m.damping_std));
  out.orders = static_cast<std::uint32_t>(m.orders);
  out.unresolved = m.unresolved;
  out.model_mode = r.model_mode[i];
  out.mac = f("mac", r.mac[i]);
  out.statement = r.statement(i);
  return out;
}

drivetrain_stiffness::PredictedMode toPredictedModeMsg(const ModalReport& r, std::size_t k) {
  auto f = [](const char* field, double value) {
    return finite("modal_identification.predicted", field, value);
  };
  const ModelModePrediction& p = r.predicted[k];
  drivetrain_stiffness::PredictedMode out;
  out.dominant = p.dominant;
  out.frequency = f("frequency", p.frequency);
  out.frequency_low = f("frequency_low", p.low);
  out.frequency_high = f("frequency_high", p.high);
  out.observability = modal::observabilityName(r.observability[k]);
  out.identified = r.identified[k];
  out.statement = r.modelStatement(k);
  return out;
}

}  // namespace

drivetrain_stiffness::ModalIdentification toModalIdentificationMsg(Stamp stamp,
                                                                   const std::string& frame_id,
                                                                   const ModalReport& r) {
  auto f = [](const char* field, double value) {
    return finite("modal_identification", field, value);
  };
  drivetrain_stiffness::ModalIdentification m;
  m.header.stamp = toRosTime(stamp);
  m.header.frame_id = frame_id;
  m.record_duration = f("record_duration", r.duration);
  m.sample_rate = f("sample_rate", r.sample_rate);
  m.torque = f("torque", r.torque);
  m.pinion_speed = f("pinion_speed", r.pinion_speed);
  m.channels = r.channels;
  for (std::size_t i = 0; i < r.modes.size(); ++i) m.modes.push_back(toIdentifiedModeMsg(r, i));
  for (std::size_t k = 0; k < r.predicted.size(); ++k)
    m.predicted.push_back(toPredictedModeMsg(r, k));
  for (const modal::FrequencyBand& b : r.order_bands) {
    m.order_band_low.push_back(f("order_band_low", b.low));
    m.order_band_high.push_back(f("order_band_high", b.high));
  }
  m.spurious_clusters = static_cast<std::uint32_t>(r.spurious_clusters);
  for (const ModalPoleRow& p : r.poles) {
    // A pole whose frequency or damping is not finite is left out of the diagram.
    if (!std::isfinite(p.frequency) || !std::isfinite(p.damping)) continue;
    m.pole_order.push_back(static_cast<std::uint16_t>(p.order));
    m.pole_frequency.push_back(p.frequency);
    m.pole_damping.push_back(p.damping);
    m.pole_frequency_std.push_back(std::isfinite(p.frequency_std) ? p.frequency_std : 0.0);
    m.pole_damping_std.push_back(std::isfinite(p.damping_std) ? p.damping_std : 0.0);
    m.pole_status.push_back(modal::poleStatusName(p.status));
    m.pole_mode.push_back(p.mode);
  }
  return m;
}

std::string calibrationStatus(const RigPipeline& pipeline) {
  if (const Calibrator* c = pipeline.calibrator()) {
    const CalibrationEstimate& e = c->estimate();
    if (e.windows == 0 && e.modal_updates > 0)
      return "natural frequencies of " + std::to_string(e.modal_updates) +
             " records; waiting for the first window (a gear turn at a steady torque)";
    return e.windows == 0 ? "waiting for the first window (a gear turn at a steady torque)"
                          : toString(e.outcome);
  }
  if (!pipeline.rig().calibration.present) return "off: the gearbox has no calibration block";
  if (!pipeline.options().calibrate) return "off: ~calibrate is false";
  return "off: the gearbox has no dynamics block (the calibration needs its masses)";
}

std::string identifiedParameters(const CalibrationEstimate& estimate) {
  std::string names;
  for (int i = 0; i < kCalibrationSize; ++i) {
    if (!estimate.identified[static_cast<std::size_t>(i)]) continue;
    if (!names.empty()) names += ", ";
    names += calibrationName(i);
  }
  return names.empty() ? "none" : names;
}

}  // namespace drivetrain_stiffness

namespace drivetrain_stiffness {

std::string jointNamesOf(const sensor_msgs::JointState& msg) {
  if (msg.name.empty()) return "no joint names";
  std::string names = "joints ";
  for (std::size_t i = 0; i < msg.name.size(); ++i) {
    if (i == 4 && msg.name.size() > 5)
      return names + ", ... (" + std::to_string(msg.name.size()) + " in all)";
    names += (i ? ", '" : "'") + printableText(msg.name[i]) + "'";
  }
  return names;
}

std::optional<MotionInput> toMotionInput(const sensor_msgs::JointState& msg,
                                         const JointNames& names, std::string& why) {
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
    why = p < 0 ? "no joint named '" + names.pinion + "' (~pinion_joint); the message has " +
                      jointNamesOf(msg)
                : "joint '" + names.pinion + "' has no position (" +
                      std::to_string(msg.position.size()) + " positions for " +
                      std::to_string(msg.name.size()) + " names)";
    return std::nullopt;
  }
  MotionInput m;
  m.pinion_angle = msg.position[static_cast<std::size_t>(p)];
  if (static_cast<std::size_t>(p) < msg.velocity.size())
    m.pinion_velocity = msg.velocity[static_cast<std::size_t>(p)];
  const long g = index(names.gear);
  if (g >= 0 && static_cast<std::size_t>(g) < msg.position.size())
    m.gear_angle = msg.position[static_cast<std::size_t>(g)];
  return m;
}

}  // namespace drivetrain_stiffness

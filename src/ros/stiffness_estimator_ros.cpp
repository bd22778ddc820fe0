#include "drivetrain_stiffness/ros/stiffness_estimator_ros.hpp"

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

double positiveParam(const ros::NodeHandle& pnh, const std::string& name, double fallback) {
  double value = fallback;
  pnh.param(name, value, fallback);
  requirePositive("~" + name, value);
  return value;
}

}  // namespace

StiffnessEstimatorRos::StiffnessEstimatorRos(ros::NodeHandle nh, ros::NodeHandle pnh) : diagnostics_(nh, pnh) {
  std::string gearbox_config;
  if (!pnh.getParam("gearbox_config", gearbox_config) || gearbox_config.empty()) {
    throw InvalidInput("~gearbox_config: required parameter (path to a gearbox YAML file) is missing");
  }
  EstimatorLimits limits;
  limits.max_abs_torque = positiveParam(pnh, "max_abs_torque", limits.max_abs_torque);
  limits.max_preload = positiveParam(pnh, "max_preload", limits.max_preload);
  limits.max_interference = positiveParam(pnh, "max_interference", limits.max_interference);
  const RigConfig rig = loadRigFile(gearbox_config);
  estimator_ = std::make_unique<StiffnessEstimator>(rig, limits);
  resonance_threshold_ = positiveParam(pnh, "resonance_threshold", 0.01);
  bool dynamics = rig.dynamics.present;
  pnh.param("dynamics", dynamics, dynamics);
  if (dynamics) {
    const double rate = positiveParam(pnh, "output_rate", 1000.0);
    max_gap_ = positiveParam(pnh, "max_gap", 1.0);
    dynamics_ = std::make_unique<DynamicsEstimator>(rig, shaftBearingStiffness(), rate);
    int window = 1024, hop = 256;
    pnh.param("spectrum_window", window, window);
    pnh.param("spectrum_hop", hop, hop);
    te_spectrum_ = std::make_unique<SlidingSpectrum>(window, hop, dynamics_->outputInterval(), 3);
  }
  // One speed for both mesh phases (stiffness and dynamics): the dynamics block's, unless overridden.
  double speed_rpm = rig.dynamics.present ? rig.dynamics.speed_rpm : 1000.0;  // seed 000 Table 1
  pnh.param("pinion_speed_rpm", speed_rpm, speed_rpm);
  requireFinite("~pinion_speed_rpm", speed_rpm);
  pinion_speed_ = speed_rpm * 2.0 * M_PI / 60.0;

  diagnostics_.setHardwareID("drivetrain_stiffness");
  diagnostics_.add("stiffness_estimator", this, &StiffnessEstimatorRos::diagnose);
  stiffness_pub_ = nh.advertise<drivetrain_stiffness::Stiffness>("stiffness", 10);
  // A torque input can release many samples at once (the gap since the previous input).
  te_pub_ = nh.advertise<drivetrain_stiffness::TransmissionError>("transmission_error", 10000);
  resonance_pub_ = nh.advertise<drivetrain_stiffness::Resonance>("resonance", 10, true);  // latched: the last estimate
  spectrum_pub_ = nh.advertise<drivetrain_stiffness::SpectralPeaks>("te_spectrum", 100);
  // Relative topic names, so launch files can remap and namespace them (wiki.ros.org/Names).
  torque_sub_ = nh.subscribe("torque", 100, &StiffnessEstimatorRos::onTorque, this, ros::TransportHints().tcpNoDelay());
  preload_sub_ = nh.subscribe("preload", 10, &StiffnessEstimatorRos::onPreload, this);
  // The updater publishes at ~diagnostic_period; poll it often enough to keep that period.
  diagnostic_timer_ = nh.createTimer(ros::Duration(0.05), [this](const ros::TimerEvent&) { diagnostics_.update(); });
  ROS_INFO("stiffness_estimator: %zu bearing supports from %s", estimator_->rig().bearings.size(), gearbox_config.c_str());
}

template <typename Update>
bool StiffnessEstimatorRos::apply(const std::string& topic, const std_msgs::Header& header, std::uint64_t& accepted,
                                  std::uint64_t& rejected, Update update) {
  try {
    const StiffnessEstimate& estimate = update();
    ++accepted;
    publish(header, estimate);
    if (dynamics_) {
      // Every accepted input hands the new bearing stiffness to the dynamics (the model is rebuilt
      // only when it moved by more than 1 %), then the resonance estimate is refreshed.
      try {
        dynamics_->setBearingStiffness(shaftBearingStiffness());
      } catch (const std::exception& e) {
        ++dynamics_errors_;
        last_rejection_ = std::string("dynamics: ") + e.what();
      }
      updateResonance(header, estimate);
    }
    return true;
  } catch (const InvalidInput& e) {
    ++rejected;
    reject(topic, e.what());
  } catch (const UnreachableLoad& e) {
    ++rejected;
    ++unreachable_;
    reject(topic, e.what());
  }
  return false;
}

void StiffnessEstimatorRos::onTorque(const geometry_msgs::WrenchStamped::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool accepted = apply("torque", msg->header, accepted_torque_, rejected_torque_,
        [&]() -> const StiffnessEstimate& { return estimator_->setTorque(msg->wrench.torque.z, pinionAngle(msg->header.stamp)); });
  if (accepted && dynamics_) advanceDynamics(msg->header.stamp, msg->wrench.torque.z);
}

std::array<double, 2> StiffnessEstimatorRos::shaftBearingStiffness() const { return estimator_->shaftRadialStiffness(); }

void StiffnessEstimatorRos::advanceDynamics(const ros::Time& stamp, double torque) {
  try {
    const double t = stamp.toSec();
    const bool backwards = dynamics_->started() && t < dynamics_->time();
    const bool gap = dynamics_->started() && t - dynamics_->time() > max_gap_;
    if (!dynamics_->started() || backwards || gap) {
      // Documented rule: time going back (a looping bag) or a gap longer than ~max_gap (a paused
      // rig, a stamp of 0 before real ones) restarts the model at this input instead of integrating.
      if (backwards || gap) {
        ++time_jumps_;
        last_rejection_ = std::string(backwards ? "time went backwards" : "input gap longer than ~max_gap") + " to " +
                          std::to_string(t) + " s: dynamics reset";
      }
      dynamics_->reset(t, torque);
      te_spectrum_->reset();  // a new window: no samples from before the restart
      angle_origin_ = stamp;  // the stiffness message's mesh phase restarts with the dynamics
      return;
    }
    const double sim = t - dynamics_->time();
    const ros::WallTime start = ros::WallTime::now();
    dynamics_->advanceTo(t, [&](const DynamicsSample& s) {
      drivetrain_stiffness::TransmissionError m;
      m.header.stamp = ros::Time(s.t);
      m.header.frame_id = "pinion";
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
      te_pub_.publish(m);
      ++te_published_;
      if (te_spectrum_->push(s.dynamic_te)) {
        drivetrain_stiffness::SpectralPeaks peaks;
        peaks.header = m.header;
        for (const SpectralPeak& p : te_spectrum_->peaks()) {
          peaks.frequencies_hz.push_back(p.frequency);
          peaks.amplitudes.push_back(p.amplitude);
        }
        peaks.window_s = te_spectrum_->windowSeconds();
        peaks.resolution_hz = te_spectrum_->resolution();
        spectrum_pub_.publish(peaks);
      }
    });
    dynamics_sim_s_ += sim;
    dynamics_wall_s_ += (ros::WallTime::now() - start).toSec();
  } catch (const std::exception& e) {
    ++dynamics_errors_;
    last_rejection_ = std::string("dynamics: ") + e.what();
  }
  try {
    dynamics_->setTorque(torque);  // the new torque holds from here on, whatever happened above
  } catch (const std::exception& e) {
    ++dynamics_errors_;
    last_rejection_ = std::string("dynamics: ") + e.what();
  }
}

void StiffnessEstimatorRos::onPreload(const drivetrain_stiffness::Preload::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<PreloadSetting> settings;
  for (const auto& b : msg->bearings) {
    settings.push_back({b.name, b.axial_preload, b.radial_preload, b.inner_interference, b.outer_interference});
  }
  apply("preload", msg->header, accepted_preload_, rejected_preload_,
        [&]() -> const StiffnessEstimate& { return estimator_->setPreloads(settings); });
}

void StiffnessEstimatorRos::updateResonance(const std_msgs::Header& header, const StiffnessEstimate& estimate) {
  try {
    const std::array<double, 2> kb = shaftBearingStiffness();
    const GearRotorParameters p = rigRotorParameters(estimator_->rig(), estimator_->mesh(), kb);
    const std::array<Mode, 3> modes = modalAnalysis(p, estimate.mesh.mean);
    bool moved = last_resonance_hz_.size() != modes.size();
    for (std::size_t i = 0; !moved && i < modes.size(); ++i) {
      moved = std::abs(modes[i].natural_frequency - last_resonance_hz_[i]) > resonance_threshold_ * last_resonance_hz_[i];
    }
    if (!moved) return;
    drivetrain_stiffness::Resonance r;
    r.header = header;
    last_resonance_hz_.clear();
    for (const Mode& m : modes) {
      if (!std::isfinite(m.natural_frequency) || !std::isfinite(m.damping_ratio)) return;  // never NaN on a topic
      r.frequencies_hz.push_back(m.natural_frequency);
      r.damped_frequencies_hz.push_back(m.damped_frequency);
      r.damping_ratios.push_back(m.damping_ratio);
      r.dominant_coordinate.push_back(m.dominant);
      last_resonance_hz_.push_back(m.natural_frequency);
    }
    double margin = 0.0;
    r.floquet_valid = dynamics_->floquetMargin(&margin) && std::isfinite(margin);
    r.floquet_margin = r.floquet_valid ? margin : 0.0;
    r.source = "modal: bearing model at this load, mean composite mesh stiffness of the flank state; "
               "Floquet: exact monodromy of the mesh period";
    resonance_pub_.publish(r);
    ++resonance_published_;
  } catch (const std::exception& e) {
    ++dynamics_errors_;
    last_rejection_ = std::string("resonance: ") + e.what();
  }
}

double StiffnessEstimatorRos::pinionAngle(const ros::Time& stamp) {
  // Until the dynamics integrate the rotation (issue 4), the pinion turns at the nominal speed:
  // angle = omega (t - t0) with t0 the first torque stamp, so replayed data give the same phases.
  if (!angle_origin_) angle_origin_ = stamp;
  return pinion_speed_ * (stamp - *angle_origin_).toSec();
}

void StiffnessEstimatorRos::publish(const std_msgs::Header& header, const StiffnessEstimate& estimate) {
  drivetrain_stiffness::Stiffness out;
  out.header = header;
  out.torque = estimate.torque;
  out.mesh_force = estimate.mesh_force;
  out.mesh_phase = estimate.mesh.phase;
  out.mesh_stiffness = estimate.mesh.current.composite;
  out.mesh_stiffness_mean = estimate.mesh.mean;
  out.mesh_stiffness_drive = estimate.mesh.current.k1;
  out.mesh_stiffness_back = estimate.mesh.current.k2;
  out.drive_flank_loaded = estimate.mesh.current.contact != FlankContact::kBackOnly;
  out.back_flank_loaded = estimate.mesh.current.contact != FlankContact::kDriveOnly;
  for (const SupportEstimate& s : estimate.supports) {
    drivetrain_stiffness::BearingStiffness b;
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
    out.bearings.push_back(b);
  }
  stiffness_pub_.publish(out);
}

void StiffnessEstimatorRos::reject(const std::string& topic, const std::string& reason) {
  last_rejection_ = topic + ": " + reason;
  ROS_WARN_THROTTLE(1.0, "stiffness_estimator rejected %s", last_rejection_.c_str());
}

void StiffnessEstimatorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::uint64_t rejected = rejected_torque_ + rejected_preload_;
  if (rejected > rejected_at_last_report_) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%llu inputs rejected since last report; last: %s",
                    static_cast<unsigned long long>(rejected - rejected_at_last_report_), last_rejection_.c_str());
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "estimating");
  }
  rejected_at_last_report_ = rejected;
  status.add("accepted_torque", accepted_torque_);
  status.add("rejected_torque", rejected_torque_);
  status.add("accepted_preload", accepted_preload_);
  status.add("rejected_preload", rejected_preload_);
  status.add("unreachable_loads", unreachable_);
  status.add("last_rejection", last_rejection_);
  for (const SupportEstimate& s : estimator_->current().supports) {
    status.add(s.name + ".radial_stiffness [N/m]", s.solution.radialStiffness());
  }
  if (dynamics_) {
    status.add("transmission_error_published", te_published_);
    status.add("dynamics_output_interval [s]", dynamics_->outputInterval());
    status.add("dynamics_exact_propagation", dynamics_->exact() ? "yes" : "no (bearing clearance: dopri5)");
    status.add("dynamics_dopri5_intervals", dynamics_->fallbackIntervals());
    status.add("dynamics_rebuilds", dynamics_->rebuilds());
    status.add("time_jumps_reset", time_jumps_);
    status.add("dynamics_errors", dynamics_errors_);
    status.add("resonance_published", resonance_published_);
    const double rtf = dynamics_wall_s_ > 0.0 ? dynamics_sim_s_ / dynamics_wall_s_ : 0.0;
    status.add("dynamics_realtime_factor", rtf);
    // Real-time margin: the fraction of wall time left over while keeping up with the rig.
    status.add("dynamics_realtime_margin", rtf > 0.0 ? 1.0 - 1.0 / rtf : 0.0);
    if (rtf > 0.0 && rtf < 1.0) status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN, "dynamics slower than real time");
  }
}

}  // namespace drivetrain_stiffness

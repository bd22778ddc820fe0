#include "drivetrain_stiffness/ros/stiffness_estimator_ros.hpp"

#include "drivetrain_stiffness/config/yaml_config.hpp"
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
  estimator_ = std::make_unique<StiffnessEstimator>(loadRigFile(gearbox_config), limits);
  double speed_rpm = 1000.0;  // seed 000 Table 1
  pnh.param("pinion_speed_rpm", speed_rpm, speed_rpm);
  requireFinite("~pinion_speed_rpm", speed_rpm);
  pinion_speed_ = speed_rpm * 2.0 * M_PI / 60.0;

  diagnostics_.setHardwareID("drivetrain_stiffness");
  diagnostics_.add("stiffness_estimator", this, &StiffnessEstimatorRos::diagnose);
  stiffness_pub_ = nh.advertise<drivetrain_stiffness::Stiffness>("stiffness", 10);
  // Relative topic names, so launch files can remap and namespace them (wiki.ros.org/Names).
  torque_sub_ = nh.subscribe("torque", 100, &StiffnessEstimatorRos::onTorque, this, ros::TransportHints().tcpNoDelay());
  preload_sub_ = nh.subscribe("preload", 10, &StiffnessEstimatorRos::onPreload, this);
  // The updater publishes at ~diagnostic_period; poll it often enough to keep that period.
  diagnostic_timer_ = nh.createTimer(ros::Duration(0.05), [this](const ros::TimerEvent&) { diagnostics_.update(); });
  ROS_INFO("stiffness_estimator: %zu bearing supports from %s", estimator_->rig().bearings.size(), gearbox_config.c_str());
}

template <typename Update>
void StiffnessEstimatorRos::apply(const std::string& topic, const std_msgs::Header& header, std::uint64_t& accepted,
                                  std::uint64_t& rejected, Update update) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    const StiffnessEstimate& estimate = update();
    ++accepted;
    publish(header, estimate);
  } catch (const InvalidInput& e) {
    ++rejected;
    reject(topic, e.what());
  } catch (const UnreachableLoad& e) {
    ++rejected;
    ++unreachable_;
    reject(topic, e.what());
  }
}

void StiffnessEstimatorRos::onTorque(const geometry_msgs::WrenchStamped::ConstPtr& msg) {
  apply("torque", msg->header, accepted_torque_, rejected_torque_,
        [&]() -> const StiffnessEstimate& { return estimator_->setTorque(msg->wrench.torque.z, pinionAngle(msg->header.stamp)); });
}

void StiffnessEstimatorRos::onPreload(const drivetrain_stiffness::Preload::ConstPtr& msg) {
  std::vector<PreloadSetting> settings;
  for (const auto& b : msg->bearings) {
    settings.push_back({b.name, b.axial_preload, b.radial_preload, b.inner_interference, b.outer_interference});
  }
  apply("preload", msg->header, accepted_preload_, rejected_preload_,
        [&]() -> const StiffnessEstimate& { return estimator_->setPreloads(settings); });
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
}

}  // namespace drivetrain_stiffness

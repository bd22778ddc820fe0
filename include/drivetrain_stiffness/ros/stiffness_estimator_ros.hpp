// ROS wrapper of the core StiffnessEstimator: reads and validates its parameters once, owns the
// subscribers, publishers and diagnostics, and converts messages at the edges. All physics lives
// in the core library; this class only decides what to accept and what to publish.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>

#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/Resonance.h"
#include "drivetrain_stiffness/SpectralPeaks.h"
#include "drivetrain_stiffness/spectral/sliding_spectrum.hpp"
#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"
#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

namespace drivetrain_stiffness {

class StiffnessEstimatorRos {
 public:
  /// Throws InvalidInput (naming the parameter) when a parameter or the gearbox file is invalid.
  StiffnessEstimatorRos(ros::NodeHandle nh, ros::NodeHandle pnh);

 private:
  void onTorque(const geometry_msgs::WrenchStamped::ConstPtr& msg);
  void onPreload(const drivetrain_stiffness::Preload::ConstPtr& msg);
  /// Runs one estimator update under the lock: publishes on success, counts and reports a rejection.
  /// Returns whether the input was accepted.
  template <typename Update>
  bool apply(const std::string& topic, const std_msgs::Header& header, std::uint64_t& accepted,
             std::uint64_t& rejected, Update update);
  /// Integrates the dynamics up to `stamp` with the previous torque, publishing every sample, then
  /// holds `torque`. Resets on the first input and when time went backwards.
  void advanceDynamics(const ros::Time& stamp, double torque);
  std::array<double, 2> shaftBearingStiffness() const;
  /// Publishes `resonance` when a natural frequency moved by more than ~resonance_threshold.
  void updateResonance(const std_msgs::Header& header, const StiffnessEstimate& estimate);
  void publish(const std_msgs::Header& header, const StiffnessEstimate& estimate);
  double pinionAngle(const ros::Time& stamp);
  void reject(const std::string& topic, const std::string& reason);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  std::unique_ptr<StiffnessEstimator> estimator_;
  ros::Subscriber torque_sub_, preload_sub_;
  ros::Publisher stiffness_pub_, te_pub_, resonance_pub_, spectrum_pub_;
  std::unique_ptr<SlidingSpectrum> te_spectrum_;
  std::vector<double> last_resonance_hz_;
  double resonance_threshold_ = 0.01;
  std::uint64_t resonance_published_ = 0;
  std::unique_ptr<DynamicsEstimator> dynamics_;
  std::uint64_t te_published_ = 0, time_jumps_ = 0, dynamics_errors_ = 0;
  double dynamics_sim_s_ = 0.0, dynamics_wall_s_ = 0.0;  // totals for the real-time factor
  double max_gap_ = 1.0;  // [s] an input gap longer than this restarts the dynamics
  ros::Timer diagnostic_timer_;
  diagnostic_updater::Updater diagnostics_;
  std::mutex mutex_;  // callbacks may run on several spinner threads (nodelet)

  std::uint64_t accepted_torque_ = 0, rejected_torque_ = 0;
  std::uint64_t accepted_preload_ = 0, rejected_preload_ = 0;
  std::uint64_t unreachable_ = 0;
  std::uint64_t rejected_at_last_report_ = 0;
  std::string last_rejection_;
  double pinion_speed_ = 0.0;                 // [rad/s]
  std::optional<ros::Time> angle_origin_;
};

}  // namespace drivetrain_stiffness

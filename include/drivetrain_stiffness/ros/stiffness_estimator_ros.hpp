// ROS wrapper of the RigPipeline (the same class the replay tool drives): reads and validates its
// parameters once, owns the subscribers, publishers, tf broadcaster, dynamic_reconfigure server and
// diagnostics, and converts at the edges. All physics and all time rules live in the pipeline;
// this class adds the ROS clock, wall-time deadlines and what the graph needs. Used by the node
// (stiffness_estimator_node.cpp) and the nodelet (stiffness_estimator_nodelet.cpp).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <boost/thread/recursive_mutex.hpp>
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/WrenchStamped.h>
#include <sensor_msgs/JointState.h>
#include <ros/ros.h>

#include "drivetrain_stiffness/EstimatorConfig.h"
#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/VibrationBlock.h"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "drivetrain_stiffness/ros/master_watch.hpp"
#include "drivetrain_stiffness/ros/message_conversion.hpp"

namespace drivetrain_stiffness {

class StiffnessEstimatorRos {
 public:
  /// Throws InvalidInput (naming the parameter and its value) when a parameter or the gearbox file
  /// is invalid.
  StiffnessEstimatorRos(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~StiffnessEstimatorRos();

 private:
  class Publishers;
  /// The constructor's parts: ~deadline, ~torque_queue_size (returned), ~diagnostic_period,
  /// ~shed_queue_age and ~master_check_period, each checked in that order (InvalidInput); the
  /// start count under this master; dynamic_reconfigure; the subscriptions and the timer.
  int readNodeLimits(const ros::NodeHandle& pnh, double& master_check_period);
  void countStart(ros::NodeHandle& pnh);
  void startReconfigure(ros::NodeHandle& pnh);
  void subscribe(ros::NodeHandle& nh, int queue);
  void onTorque(const ros::MessageEvent<const geometry_msgs::WrenchStamped>& event);
  void onPreload(const ros::MessageEvent<const drivetrain_stiffness::Preload>& event);
  void onJointStates(const ros::MessageEvent<const sensor_msgs::JointState>& event);
  void onVibration(const ros::MessageEvent<const drivetrain_stiffness::VibrationBlock>& event);
  /// The input waited in the subscriber queue for longer than ~shed_queue_age: shed its stiffness.
  Backlog backlogOf(const ros::Time& receipt) const;
  /// A new master knows nothing of this node: put its parameters there and exit, for roslaunch to
  /// respawn it (rig.launch sets respawn) into a clean registration. Called from the watch thread.
  void onMasterRestart(const std::string& old_run_id, const std::string& new_run_id);
  void onReconfigure(drivetrain_stiffness::EstimatorConfig& config, std::uint32_t level);
  /// ROS time going back (a looping bag) resets the pipeline; called under the lock.
  void observeClock();
  /// Counts the input as late when its processing took longer than ~deadline: in wall time (any
  /// cause, preemption included) and in this thread's CPU time (the node's own cost); keeps the
  /// `topic` of the input with the largest CPU time.
  void finishInput(const ros::WallTime& start, double cpu_start, const char* topic);
  /// `take()` (one input to the pipeline from `topic`, returning its outcome) under the lock after
  /// the clock check, timed against ~deadline; a refusal warned about, at most once a second per
  /// input type.
  template <typename Take>
  void handleInput(const char* topic, const Take& take);
  void onDiagnosticTimer();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  /// diagnose's parts, in the order they add to `status` (called under the lock).
  void summarizeSinceLastReport(diagnostic_updater::DiagnosticStatusWrapper& status,
                                const PipelineCounters& c);
  void addInputStatus(diagnostic_updater::DiagnosticStatusWrapper& status,
                      const PipelineDiagnostics& d);
  void addProcessStatus(diagnostic_updater::DiagnosticStatusWrapper& status,
                        const PipelineDiagnostics& d);
  void addCalibrationStatus(diagnostic_updater::DiagnosticStatusWrapper& status);
  void addDynamicsStatus(diagnostic_updater::DiagnosticStatusWrapper& status,
                         const PipelineDiagnostics& d);

  std::mutex mutex_;  // callbacks may run on several threads (nodelet, multi-threaded spinners)
  std::unique_ptr<RigPipeline> pipeline_;
  std::vector<PreloadSetting>
      preload_settings_;  ///< each preload message's, converted in place (under mutex_)
  std::unique_ptr<Publishers> publishers_;
  ros::Subscriber torque_sub_, preload_sub_, joint_states_sub_, vibration_sub_;
  JointNames joints_;
  std::string joint_refusal_;  ///< scratch for toMotionInput's reason
  diagnostic_updater::Updater diagnostics_;
  ros::WallTimer diagnostic_timer_;  // wall time: keeps running when sim time stops or jumps back
  boost::recursive_mutex
      reconfigure_mutex_;  // dynamic_reconfigure::Server wants a boost mutex; outlives it
  std::unique_ptr<dynamic_reconfigure::Server<drivetrain_stiffness::EstimatorConfig>> reconfigure_;
  std::optional<drivetrain_stiffness::EstimatorConfig>
      applied_config_;  // the last accepted settings
  std::string gearbox_config_;
  /// What each input cost, for /diagnostics.
  struct ProcessingLoad {
    double deadline = 1e-3;  // [s] processing time per input beyond which it counts as late
    std::uint64_t missed_deadlines = 0, missed_deadlines_cpu = 0, processed = 0;
    double processing_s = 0.0, max_processing_s = 0.0, max_processing_cpu_s = 0.0;
    const char* max_processing_cpu_topic = "";  // the input topic of max_processing_cpu_s
  } load_;
  /// The counts at the last /diagnostics report, so that it says what is new since.
  struct ReportedSoFar {
    std::uint64_t rejected = 0, resets = 0, late = 0, dropped = 0, shed = 0;
    std::uint64_t motion_timeouts = 0, ratio_mismatches = 0, calibration_errors = 0;
  } reported_;
  std::uint64_t reconfigurations_ = 0;
  double diagnostic_period_ = 1.0;  // [s] wall time between /diagnostics publications
  ros::WallTime last_diagnostic_wall_;
  double shed_queue_age_ = 0.01;  // [s] queue wait beyond which a torque input is shed; 0 = never
  int starts_ = 1;                // of this node under this master (respawns included)
  bool restart_reported_ = false;
  std::string private_namespace_;
  XmlRpc::XmlRpcValue parameters_;  // the private parameters at start-up, for a restarted master
  std::unique_ptr<MasterWatch> master_watch_;
};

}  // namespace drivetrain_stiffness

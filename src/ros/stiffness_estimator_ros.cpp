#include "drivetrain_stiffness/ros/stiffness_estimator_ros.hpp"

#include <malloc.h>
#include <time.h>

#include <fstream>

#include <tf2_ros/transform_broadcaster.h>

#include "drivetrain_stiffness/Calibration.h"
#include "drivetrain_stiffness/MeasuredTe.h"
#include "drivetrain_stiffness/MeshPeriodStats.h"
#include "drivetrain_stiffness/ModalIdentification.h"
#include "drivetrain_stiffness/Resonance.h"
#include "drivetrain_stiffness/SpectralPeaks.h"
#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/ros/message_sink.hpp"
#include "drivetrain_stiffness/ros/node_parameters.hpp"
#include "drivetrain_stiffness/ros/parameters.hpp"

namespace drivetrain_stiffness {
namespace {

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double residentMemoryKb() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      double kb = 0.0;
      status >> kb;
      return kb;
    }
    status.ignore(1 << 12, '\n');
  }
  return 0.0;
}

/// Bytes the process holds in live heap blocks (glibc, all arenas, mmapped blocks included). Unlike
/// the resident set it falls back when the queues drain, so it shows a leak apart from a queue that
/// was full once (the allocator keeps what it had).
double heapInUseBytes() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd);
}

}  // namespace

class StiffnessEstimatorRos::Publishers : public MessageSink {
 public:
  Publishers(ros::NodeHandle& nh, const RigPipeline& pipeline, const OutputSettings& settings)
      : MessageSink(pipeline, settings) {
    // Deep queues: at 10 kHz a subscriber stalled for 10 ms would otherwise lose messages to
    // roscpp's publisher queue, the one place data could vanish without a count.
    stiffness_ = nh.advertise<drivetrain_stiffness::Stiffness>("stiffness", 10000);
    // A torque input can release many samples at once (the gap since the previous input).
    te_ = nh.advertise<drivetrain_stiffness::TransmissionError>("transmission_error", 10000);
    resonance_ = nh.advertise<drivetrain_stiffness::Resonance>("resonance", 10,
                                                               true);  // latched: the last estimate
    spectrum_ = nh.advertise<drivetrain_stiffness::SpectralPeaks>("te_spectrum", 100);
    markers_ = nh.advertise<visualization_msgs::MarkerArray>("rig_markers", 10);
    // The live calibration (the calibration rule): one measured TE per encoder reading (as
    // transmission_error), one calibration per closed window. Advertised with or without a
    // calibration block, so the interface does not depend on the gearbox file.
    measured_te_ = nh.advertise<drivetrain_stiffness::MeasuredTe>("measured_te", 10000);
    calibration_ = nh.advertise<drivetrain_stiffness::Calibration>("calibration", 10000);
    // The TE and mesh force per block of whole mesh periods (~10 output samples or more each).
    mesh_period_stats_ =
        nh.advertise<drivetrain_stiffness::MeshPeriodStats>("mesh_period_stats", 1000);
    // One message per identified accelerometer record (seconds apart).
    modal_identification_ =
        nh.advertise<drivetrain_stiffness::ModalIdentification>("modal_identification", 100);
  }

 protected:
  void emitStiffness(const drivetrain_stiffness::Stiffness& m) override { stiffness_.publish(m); }
  void emitTransmissionError(const drivetrain_stiffness::TransmissionError& m) override {
    te_.publish(m);
  }
  void emitSpectrum(const drivetrain_stiffness::SpectralPeaks& m) override { spectrum_.publish(m); }
  void emitResonance(const drivetrain_stiffness::Resonance& m) override { resonance_.publish(m); }
  void emitMeasuredTe(const drivetrain_stiffness::MeasuredTe& m) override {
    measured_te_.publish(m);
  }
  void emitCalibration(const drivetrain_stiffness::Calibration& m) override {
    calibration_.publish(m);
  }
  void emitMeshPeriodStats(const drivetrain_stiffness::MeshPeriodStats& m) override {
    mesh_period_stats_.publish(m);
  }
  void emitModalIdentification(const drivetrain_stiffness::ModalIdentification& m) override {
    modal_identification_.publish(m);
  }
  void emitTransforms(const std::vector<geometry_msgs::TransformStamped>& t) override {
    tf_.sendTransform(t);
  }
  void emitMarkers(const visualization_msgs::MarkerArray& m) override { markers_.publish(m); }

 private:
  ros::Publisher stiffness_, te_, resonance_, spectrum_, markers_, measured_te_, calibration_,
      mesh_period_stats_, modal_identification_;
  tf2_ros::TransformBroadcaster tf_;
};

// The diagnostic status is named after the private namespace (the node's name, also for a nodelet,
// where ros::this_node::getName() would be the manager's).
StiffnessEstimatorRos::StiffnessEstimatorRos(ros::NodeHandle nh, ros::NodeHandle pnh)
    : diagnostics_(nh, pnh, pnh.getNamespace()) {
  gearbox_config_ = readParam<std::string>(pnh, "gearbox_config", "");
  if (gearbox_config_.empty()) {
    throw InvalidInput(
        "~gearbox_config: required parameter (path to a gearbox YAML file) is missing");
  }
  const RigConfig rig = loadRigFile(gearbox_config_);
  const auto get = [&pnh](const std::string& name, const auto& fallback) {
    return readParam(pnh, name, fallback);
  };
  PipelineOptions options = readPipelineOptions(get, rig);
  options.modal_worker = true;  // no input waits for an identification (docs/vibration.md)
  pipeline_ = std::make_unique<RigPipeline>(rig, options, readRuntimeSettings(get, rig));
  publishers_ = std::make_unique<Publishers>(nh, *pipeline_, readOutputSettings(get));
  joints_ = readJointNames(get);
  double master_check_period = 0.0;
  const int queue = readNodeLimits(pnh, master_check_period);
  countStart(pnh);
  startReconfigure(pnh);
  diagnostics_.setHardwareID("drivetrain_stiffness");
  diagnostics_.add("stiffness_estimator", this, &StiffnessEstimatorRos::diagnose);
  subscribe(nh, queue);
  private_namespace_ = pnh.getNamespace();
  pnh.getParam(private_namespace_, parameters_);
  if (master_check_period > 0.0) {
    master_watch_ = std::make_unique<MasterWatch>(
        master_check_period,
        [this](const std::string& a, const std::string& b) { onMasterRestart(a, b); });
  }
  ROS_INFO(
      "stiffness_estimator: %zu bearing supports from %s; dynamics %s; calibration %s; start %d "
      "under this master",
      rig.bearings.size(), gearbox_config_.c_str(),
      pipeline_->dynamics() ? toString(pipeline_->settings().fidelity) : "off",
      pipeline_->calibrator() ? "on" : calibrationStatus(*pipeline_).c_str(), starts_);
}

StiffnessEstimatorRos::~StiffnessEstimatorRos() = default;

int StiffnessEstimatorRos::readNodeLimits(const ros::NodeHandle& pnh, double& master_check_period) {
  load_.deadline = readParam(pnh, "deadline", load_.deadline);
  requirePositive("~deadline", load_.deadline);
  const int queue = readParam(pnh, "torque_queue_size", 1000);
  if (queue < 1 || queue > 1000000) {
    throw InvalidInput("~torque_queue_size = " + std::to_string(queue) +
                       ": must be in [1, 1000000]");
  }
  diagnostic_period_ = readParam(pnh, "diagnostic_period", diagnostic_period_);
  if (!(diagnostic_period_ > 0.0 && diagnostic_period_ <= 60.0)) {
    throw InvalidInput("~diagnostic_period = " + formatValue(diagnostic_period_) +
                       ": must be in (0, 60] s");
  }
  shed_queue_age_ = readParam(pnh, "shed_queue_age", shed_queue_age_);
  if (!(shed_queue_age_ >= 0.0 && shed_queue_age_ <= 60.0)) {
    throw InvalidInput("~shed_queue_age = " + formatValue(shed_queue_age_) +
                       ": must be in [0, 60] s (0: never shed)");
  }
  master_check_period = readParam(pnh, "master_check_period", 1.0);
  if (!(master_check_period >= 0.0 && master_check_period <= 60.0)) {
    throw InvalidInput("~master_check_period = " + formatValue(master_check_period) +
                       ": must be in [0, 60] s (0: off)");
  }
  return queue;
}

// Starts under this master: the parameter server outlives a respawned process, so a SIGKILL and
// roslaunch's respawn show up as a restart on /diagnostics. Written by the node, not a setting.
void StiffnessEstimatorRos::countStart(ros::NodeHandle& pnh) {
  int previous_starts = 0;
  pnh.getParam("process_starts", previous_starts);
  starts_ = previous_starts + 1;
  pnh.setParam("process_starts", starts_);
}

// dynamic_reconfigure starts from the parameter server: seed it with the gearbox's damping, every
// time (the server writes its values back, so a restart would otherwise reuse the last session's
// and the node would not match drivetrain_replay on the same files).
void StiffnessEstimatorRos::startReconfigure(ros::NodeHandle& pnh) {
  const RuntimeSettings& run = pipeline_->settings();
  pnh.setParam("mesh_damping_ratio", run.mesh_damping_ratio);
  pnh.setParam("bearing_damping_ratio", run.bearing_damping_ratio);
  pnh.setParam("fidelity", std::string(toString(run.fidelity)));
  pnh.setParam("exaggeration", run.exaggeration);
  pnh.setParam("stiffness_rate", run.stiffness_rate);
  pnh.setParam("tf_rate", run.tf_rate);
  reconfigure_ =
      std::make_unique<dynamic_reconfigure::Server<drivetrain_stiffness::EstimatorConfig>>(
          reconfigure_mutex_, pnh);
  reconfigure_->setCallback([this](drivetrain_stiffness::EstimatorConfig& c, std::uint32_t level) {
    onReconfigure(c, level);
  });
}

void StiffnessEstimatorRos::subscribe(ros::NodeHandle& nh, int queue) {
  // Relative topic names, so launch files can remap and namespace them (wiki.ros.org/Names).
  torque_sub_ =
      nh.subscribe("torque", static_cast<std::uint32_t>(queue), &StiffnessEstimatorRos::onTorque,
                   this, ros::TransportHints().tcpNoDelay());
  preload_sub_ = nh.subscribe("preload", 100, &StiffnessEstimatorRos::onPreload, this);
  // The rig's encoders, by the ROS convention for joint positions (sensor_msgs/JointState).
  joint_states_sub_ = nh.subscribe("joint_states", 1000, &StiffnessEstimatorRos::onJointStates,
                                   this, ros::TransportHints().tcpNoDelay());
  // Accelerometer blocks (docs/vibration.md "Input"): 100 blocks are 2 s at 51.2 kHz and 1024.
  vibration_sub_ = nh.subscribe("vibration", 100, &StiffnessEstimatorRos::onVibration, this,
                                ros::TransportHints().tcpNoDelay());
  // The updater publishes at ~diagnostic_period; poll it often enough to keep that period.
  diagnostic_timer_ = nh.createWallTimer(
      ros::WallDuration(0.05), [this](const ros::WallTimerEvent&) { onDiagnosticTimer(); });
}

void StiffnessEstimatorRos::onMasterRestart(const std::string& old_run_id,
                                            const std::string& new_run_id) {
  // The parameters go first, so that the respawned process reads the same settings it had.
  if (parameters_.valid()) ros::param::set(private_namespace_, parameters_);
  ROS_ERROR(
      "stiffness_estimator: the ROS master restarted (run_id %s -> %s): this node's topics are no "
      "longer "
      "registered; its parameters are restored and it exits for roslaunch to respawn it "
      "(rig.launch: respawn)",
      old_run_id.c_str(), new_run_id.c_str());
  ros::requestShutdown();
}

Backlog StiffnessEstimatorRos::backlogOf(const ros::Time& receipt) const {
  // Receipt time is stamped by roscpp when the message entered the subscriber queue; its age here
  // is the queue's backlog, on the same clock whatever the publisher's stamps say.
  if (shed_queue_age_ <= 0.0 || receipt.isZero()) return Backlog::kNone;
  return (ros::Time::now() - receipt).toSec() > shed_queue_age_ ? Backlog::kShed : Backlog::kNone;
}

void StiffnessEstimatorRos::observeClock() {
  if (pipeline_->observeClock(fromRosTime(ros::Time::now()), *publishers_)) {
    ROS_WARN("stiffness_estimator: %s", pipeline_->counters().last_event.c_str());
  }
}

void StiffnessEstimatorRos::finishInput(const ros::WallTime& start, double cpu_start,
                                        const char* topic) {
  const double took = (ros::WallTime::now() - start).toSec();
  const double cpu = threadCpuSeconds() - cpu_start;
  load_.processing_s += took;
  load_.max_processing_s = std::max(load_.max_processing_s, took);
  if (cpu > load_.max_processing_cpu_s) {
    load_.max_processing_cpu_s = cpu;
    load_.max_processing_cpu_topic = topic;
  }
  ++load_.processed;
  if (took > load_.deadline) ++load_.missed_deadlines;
  if (cpu > load_.deadline) ++load_.missed_deadlines_cpu;
}

template <typename Take>
void StiffnessEstimatorRos::handleInput(const char* topic, const Take& take) {
  const ros::WallTime start = ros::WallTime::now();
  const double cpu_start = threadCpuSeconds();
  std::lock_guard<std::mutex> lock(mutex_);
  observeClock();
  if (take() != InputOutcome::kAccepted) {
    ROS_WARN_THROTTLE(1.0, "stiffness_estimator: %s", pipeline_->counters().last_event.c_str());
  }
  finishInput(start, cpu_start, topic);
}

void StiffnessEstimatorRos::onTorque(
    const ros::MessageEvent<const geometry_msgs::WrenchStamped>& event) {
  handleInput("torque", [&] {
    const TorqueInput in = toTorqueInput(*event.getConstMessage(), event.getPublisherName());
    return pipeline_->torque(in.stamp, in.torque, *publishers_, in.origin,
                             backlogOf(event.getReceiptTime()));
  });
}

void StiffnessEstimatorRos::onPreload(
    const ros::MessageEvent<const drivetrain_stiffness::Preload>& event) {
  handleInput("preload", [&] {
    const drivetrain_stiffness::Preload& msg = *event.getConstMessage();
    toPreloadSettings(msg, preload_settings_);
    return pipeline_->preload(fromRosTime(msg.header.stamp), preload_settings_, *publishers_,
                              {event.getPublisherName(), msg.header.seq, msg.header.frame_id});
  });
}

void StiffnessEstimatorRos::onJointStates(
    const ros::MessageEvent<const sensor_msgs::JointState>& event) {
  handleInput("joint_states", [&] {
    const sensor_msgs::JointState& msg = *event.getConstMessage();
    const InputOrigin origin{event.getPublisherName(), msg.header.seq, msg.header.frame_id};
    const Stamp stamp = fromRosTime(msg.header.stamp);
    const std::optional<MotionInput> reading = toMotionInput(msg, joints_, joint_refusal_);
    return reading ? pipeline_->motion(stamp, *reading, *publishers_, origin)
                   : pipeline_->motionRefused(stamp, joint_refusal_, origin, jointNamesOf(msg));
  });
}

void StiffnessEstimatorRos::onVibration(
    const ros::MessageEvent<const drivetrain_stiffness::VibrationBlock>& event) {
  handleInput("vibration", [&] {
    const drivetrain_stiffness::VibrationBlock& msg = *event.getConstMessage();
    const VibrationBlockView block{msg.sample_rate, msg.channels.data(), msg.channels.size(),
                                   msg.data.data(), msg.data.size()};
    return pipeline_->vibration(fromRosTime(msg.header.stamp), block, *publishers_,
                                {event.getPublisherName(), msg.header.seq, msg.header.frame_id});
  });
}

void StiffnessEstimatorRos::onReconfigure(drivetrain_stiffness::EstimatorConfig& config,
                                          std::uint32_t /*level*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    // All or nothing: RigPipeline::apply validates the whole set before it changes anything (the
    // .cfg ranges clamp rqt's requests; a hand-made request may still carry an unknown fidelity).
    RuntimeSettings next;
    next.mesh_damping_ratio = config.mesh_damping_ratio;
    next.bearing_damping_ratio = config.bearing_damping_ratio;
    next.fidelity = parseFidelity("fidelity", config.fidelity);
    next.stiffness_rate = config.stiffness_rate;
    next.exaggeration = config.exaggeration;
    next.tf_rate = config.tf_rate;
    pipeline_->apply(next);
    publishers_->apply(
        pipeline_->settings());  // the same settings for the drawing (tf rate, exaggeration)
    applied_config_ = config;
    ++reconfigurations_;
  } catch (const InvalidInput& e) {
    ROS_ERROR("stiffness_estimator: reconfiguration refused, settings unchanged: %s", e.what());
    if (applied_config_)
      config = *applied_config_;  // what the server echoes back: the settings in force
  }
}

void StiffnessEstimatorRos::onDiagnosticTimer() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    observeClock();  // also while no input arrives (a paused, looping bag)
  }
  // diagnostic_updater schedules its runs on ROS time, which stops when a bag ends and jumps back
  // when it loops (it would then stay silent for the length of the jump; robot_localization forces
  // an update for the same reason). /diagnostics is about the process, so it runs on wall time.
  const ros::WallTime wall = ros::WallTime::now();
  if ((wall - last_diagnostic_wall_).toSec() >= diagnostic_period_) {
    last_diagnostic_wall_ = wall;
    diagnostics_.force_update();
  }
}

void StiffnessEstimatorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  const PipelineDiagnostics d = pipeline_->diagnostics(fromRosTime(ros::Time::now()));
  summarizeSinceLastReport(status, d.counters);
  addInputStatus(status, d);
  addProcessStatus(status, d);
  addCalibrationStatus(status);
  addDynamicsStatus(status, d);
}

void StiffnessEstimatorRos::summarizeSinceLastReport(
    diagnostic_updater::DiagnosticStatusWrapper& status, const PipelineCounters& c) {
  const std::uint64_t rejected = c.rejected_torque + c.rejected_preload + c.rejected_motion;
  const std::uint64_t dropped = c.dropped_torque + c.dropped_preload + c.dropped_motion;
  const std::uint64_t resets = c.clock_resets + c.stamp_resets + c.gap_restarts;
  status.summary(diagnostic_msgs::DiagnosticStatus::OK, "estimating");
  if (rejected > reported_.rejected) {
    status.summaryf(
        diagnostic_msgs::DiagnosticStatus::WARN, "%llu inputs rejected since last report; last: %s",
        static_cast<unsigned long long>(rejected - reported_.rejected), c.last_event.c_str());
  }
  if (resets > reported_.resets) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN, "estimator reset: %s",
                         c.last_event.c_str());
  }
  if (dropped > reported_.dropped) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "%llu inputs dropped on the way since last report",
                         static_cast<unsigned long long>(dropped - reported_.dropped));
  }
  if (c.motion_timeouts > reported_.motion_timeouts) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "encoders silent for ~motion_timeout: phase from ~pinion_speed_rpm");
  }
  if (c.gear_ratio_mismatches > reported_.ratio_mismatches) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "gear angle off the tooth ratio: %s", c.last_event.c_str());
  }
  if (c.calibration_errors > reported_.calibration_errors) {
    status.mergeSummaryf(
        diagnostic_msgs::DiagnosticStatus::WARN,
        "%llu calibration errors since last report; last: %s",
        static_cast<unsigned long long>(c.calibration_errors - reported_.calibration_errors),
        c.last_event.c_str());
  }
  reported_.calibration_errors = c.calibration_errors;
  reported_.motion_timeouts = c.motion_timeouts;
  reported_.ratio_mismatches = c.gear_ratio_mismatches;
  if (c.stiffness_shed > reported_.shed) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "overloaded: %llu torque inputs shed since last report",
                         static_cast<unsigned long long>(c.stiffness_shed - reported_.shed));
  }
  if (starts_ > 1 && !restart_reported_) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "restarted (start %d under this master)", starts_);
    restart_reported_ = true;
  }
  reported_.rejected = rejected;
  reported_.resets = resets;
  reported_.dropped = dropped;
  reported_.shed = c.stiffness_shed;
}

void StiffnessEstimatorRos::addInputStatus(diagnostic_updater::DiagnosticStatusWrapper& status,
                                           const PipelineDiagnostics& d) {
  for (const auto& [key, count] : namedCounters(d.counters)) status.add(key, count);
  status.add("last_event", d.counters.last_event);
  status.add("phase_source", d.phase_source);
  if (!d.unknown_vibration_channels.empty()) {
    std::string names;
    for (const std::string& n : d.unknown_vibration_channels)
      names += (names.empty() ? "" : ", ") + n;
    status.add("vibration_unknown_channel_names", names);
  }
  // The time-out is taken on the next input's stamp (the encoders rule): with every input stopped,
  // the age of the last reading on the node's clock says that the phase source above is stale.
  if (const std::optional<double> silence = d.encoder_silence) {
    status.add("encoder_silence [s]", *silence);
    if (*silence > pipeline_->options().motion_timeout) {
      status.mergeSummaryf(
          diagnostic_msgs::DiagnosticStatus::WARN,
          "no joint_states for %.3g s (more than ~motion_timeout) and no input since: the phase "
          "falls back to ~pinion_speed_rpm at the next one",
          *silence);
    }
  }
}

void StiffnessEstimatorRos::addProcessStatus(diagnostic_updater::DiagnosticStatusWrapper& status,
                                             const PipelineDiagnostics& d) {
  status.add("process_restarts", starts_ - 1);
  status.add("unnumbered_publishers", d.unnumbered_publishers);
  status.add("missed_deadlines", load_.missed_deadlines);
  status.add("missed_deadlines_cpu", load_.missed_deadlines_cpu);
  status.add("deadline [s]", load_.deadline);
  status.add("mean_processing [s]", load_.processed ? load_.processing_s / load_.processed : 0.0);
  status.add("max_processing [s]", load_.max_processing_s);
  status.add("max_processing_cpu [s]", load_.max_processing_cpu_s);
  status.add("max_processing_cpu_topic", load_.max_processing_cpu_topic);
  status.add("resident_memory [kB]", residentMemoryKb());
  status.add("heap_in_use [B]", heapInUseBytes());
  status.add("reconfigurations", reconfigurations_);
  for (const SupportEstimate& s : pipeline_->estimator().current().supports) {
    status.add(s.name + ".radial_stiffness [N/m]", s.solution.radialStiffness());
  }
  if (load_.missed_deadlines > reported_.late) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "%llu inputs took longer than ~deadline since last report",
                         static_cast<unsigned long long>(load_.missed_deadlines - reported_.late));
  }
  reported_.late = load_.missed_deadlines;
}

void StiffnessEstimatorRos::addCalibrationStatus(
    diagnostic_updater::DiagnosticStatusWrapper& status) {
  // The live calibration (the calibration rule): the last window's outcome, its counts and what the
  // data determined.
  status.add("calibration", calibrationStatus(*pipeline_));
  if (const Calibrator* calibrator = pipeline_->calibrator()) {
    const CalibrationEstimate& e = calibrator->estimate();
    status.add("calibration_windows", e.windows);
    status.add("calibration_baseline_windows", e.baseline_windows);
    status.add("calibration_updates", e.updates);
    status.add("calibration_gated", e.gated);
    status.add("calibration_not_excited", e.not_excited);
    status.add("calibration_nis", e.nis);
    status.add("calibration_identified", identifiedParameters(e));
    // Until a window updates the calibration, why not, with the numbers. A WARN once readings with
    // the gear angle arrive and still no window updates (a calibration that never starts is
    // otherwise silent); a rig without the gear encoder is told, not warned, every second.
    const std::string waiting = calibrator->waitingReason();
    status.add("calibration_waiting", waiting.empty() ? "no" : waiting);
    if (!waiting.empty() && calibrator->progress().readings > 0) {
      status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN, "calibration waiting: %s",
                           waiting.c_str());
    }
    static const char* const units[kCalibrationSize] = {"[-]", "[-]", "[-]", "[N*m]",
                                                        "[m]"};  // CalibrationIndex order
    for (int i = 0; i < kCalibrationSize; ++i) {
      status.addf(std::string("calibration.") + calibrationName(i) + " " + units[i], "%.6g +- %.2g",
                  e.value[i], e.std[i]);
    }
  }
}

void StiffnessEstimatorRos::addDynamicsStatus(diagnostic_updater::DiagnosticStatusWrapper& status,
                                              const PipelineDiagnostics& d) {
  if (d.dynamics) {
    status.add("dynamics_fidelity", toString(d.dynamics->fidelity));
    status.add("dynamics_output_interval [s]", d.dynamics->output_interval);
    const DynamicsWork& work = d.dynamics->work;
    status.add("dynamics_exact_propagation", work.exact ? "yes" : "no (bearing clearance: dopri5)");
    status.add("dynamics_dopri5_intervals", work.fallback_intervals);
    status.add("dynamics_rebuilds", work.rebuilds);
    // Real-time factor: model time integrated per second of processing.
    const double rtf = load_.processing_s > 0.0 ? d.counters.simulated_s / load_.processing_s : 0.0;
    status.add("realtime_factor", rtf);
    if (rtf > 0.0 && rtf < 1.0)
      status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN, "slower than real time");
  }
}

}  // namespace drivetrain_stiffness

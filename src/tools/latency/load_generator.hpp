// Load on the stiffness_estimator node as a rig would give it: torque at a fixed rate, stamped with
// the send time, and what comes back measured from outside the node. Input-to-output latency is
// receipt time - header.stamp of each stiffness answer (the node copies the input's stamp), so it
// includes both transports and the node's queueing, not just its processing. Wall clock only: the
// stamps must be comparable with ros::Time::now() at receipt (no /use_sim_time).
// Used by the drivetrain_latency tool and the soak rostest.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nlohmann/json.hpp>
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"
#include "drivetrain_stiffness/VibrationBlock.h"
#include "drivetrain_stiffness/pipeline/sequence_gaps.hpp"

namespace drivetrain_stiffness {

struct LoadOptions {
  double rate_hz =
      1000.0;  ///< [Hz] torque send rate; 0 = as fast as publish() goes (outruns the node)
  double duration_s = 10.0;  ///< [s] sending time
  double warmup_s = 2.0;     ///< [s] after the first send: the first RSS after it is the baseline
  double connect_timeout_s = 20.0;  ///< [s] for the node to appear on all three topics
  double settle_timeout_s =
      10.0;                     ///< [s] after the last send, for the last answers and diagnostics
  double nominal_torque = 0.1;  ///< [N*m] seed rig nominal
  double ripple_torque = 0.01;  ///< [N*m] amplitude of the ripple
  double ripple_hz = 100.0;     ///< [Hz] ripple frequency
  std::string diagnostic_status = "stiffness_estimator: stiffness_estimator";
  /// [Hz] accelerometer sample rate of the vibration blocks sent beside the torque (2 channels,
  /// the seed gearbox's supports, Gaussian noise); 0: none.
  double vibration_rate_hz = 0.0;
  int vibration_block = 1024;  ///< frames per block
};

/// NaN where nothing was measured (no answer, no diagnostics after the warm-up).
struct LoadResult {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  std::uint64_t sent = 0, answered = 0;
  std::uint64_t answers_lost =
      0;  ///< stiffness answers the node published that never arrived (seq gaps)
  std::uint64_t te_received = 0,
                te_lost = 0;         ///< transmission_error samples received, and lost (seq gaps)
  std::uint64_t non_finite = 0;      ///< answers or samples with a NaN or Inf in a number field
  std::uint64_t late_sends = 0;      ///< sent more than one period after their deadline
  double max_send_lateness_s = 0.0;  ///< [s] worst send time - deadline
  double send_rate_hz = 0.0;         ///< [Hz] mean rate between the first and the last send
  double latency_p50_s = kNone, latency_p90_s = kNone, latency_p99_s = kNone, latency_max_s = kNone;
  // From the node's /diagnostics (its counters since it started).
  bool diagnostics_seen = false;
  double rss_warmup_kb = kNone, rss_end_kb = kNone;  ///< [kB] VmRSS of the node
  double heap_end_b = kNone;  ///< [B] the node's live heap at the end (queues drained)
  std::uint64_t accepted_torque = 0, rejected_torque = 0, missed_deadlines = 0,
                stiffness_published = 0;
  std::uint64_t dropped_torque = 0, stiffness_shed = 0, stiffness_coalesced = 0, te_published = 0;
  std::uint64_t missed_deadlines_warmup = 0;
  std::uint64_t missed_deadlines_cpu = 0;         ///< the node's own CPU time beyond ~deadline
  std::uint64_t missed_deadlines_cpu_warmup = 0;  ///< of those, by the RSS baseline report
  double max_processing_cpu_s = kNone;   ///< of missed_deadlines, those by the RSS baseline report
  std::string max_processing_cpu_topic;  ///< the input topic of max_processing_cpu_s
  double max_processing_s = kNone, mean_processing_s = kNone;
  std::uint64_t vibration_sent = 0, accepted_vibration = 0;  ///< blocks
  std::uint64_t modal_published = 0;  ///< the node's identifications since it started
};

nlohmann::json toJson(const LoadResult& r);

class LoadGenerator {
 public:
  /// Topics are resolved in `nh`'s namespace (torque, stiffness) and /diagnostics.
  LoadGenerator(const ros::NodeHandle& nh, const LoadOptions& options);
  ~LoadGenerator();

  /// Waits for the node on torque, stiffness and /diagnostics; false on timeout.
  bool connect();
  /// Sends for duration_s, then waits for the answers and a fresh diagnostics report.
  LoadResult run();

 private:
  /// run()'s parts: sends `total` torque inputs on schedule (the result holds the send counts),
  /// waits until the node has accounted for `sent` since `baseline`, and merges the node's counts
  /// with `sends` and the latencies.
  LoadResult send(std::uint64_t total);
  void settle(const LoadResult& baseline, std::uint64_t sent);
  LoadResult collect(const LoadResult& sends);
  void onStiffness(const Stiffness::ConstPtr& msg);
  void onTransmissionError(const TransmissionError::ConstPtr& msg);
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg);
  /// Waits (wall time) until done() or the timeout; done() is called under mutex_.
  template <typename F>
  bool waitFor(F done, double timeout_s);

  LoadOptions options_;
  ros::CallbackQueue queue_;  // own queue: the spinner serves only these subscriptions
  ros::NodeHandle nh_;
  ros::Publisher torque_pub_, vibration_pub_;
  ros::Subscriber stiffness_sub_, te_sub_, diagnostics_sub_;
  std::uint32_t next_seq_ = 0;  // header.seq of the next torque sent: the node counts gaps as drops
  std::unique_ptr<ros::AsyncSpinner> spinner_;

  std::mutex mutex_;  // the spinner's thread writes, run() reads
  std::vector<double> latencies_s_;
  SequenceGaps answer_gaps_, te_gaps_;
  std::uint64_t answers_lost_ = 0, te_received_ = 0, te_lost_ = 0, non_finite_ = 0;
  ros::WallTime warmup_end_;  // zero until run() starts: no RSS baseline before that
  std::uint64_t diagnostics_received_ = 0;
  LoadResult diag_;  // diagnostics fields only
};

}  // namespace drivetrain_stiffness

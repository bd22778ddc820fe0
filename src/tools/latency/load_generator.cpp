#include "load_generator.hpp"

#include <sys/prctl.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <thread>

#include <geometry_msgs/WrenchStamped.h>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {
namespace {

/// Nearest-rank percentile of a sorted, non-empty vector: the smallest value with at least p % of
/// the samples at or below it (no interpolation: every reported latency was actually observed).
double percentile(const std::vector<double>& sorted, double p) {
  const auto rank =
      static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

/// Sleeps to just before the deadline, then spins: the sleep leaves the core to the node (the
/// 2-core test machines), the spin absorbs the sleep's wake-up jitter.
void waitUntil(const ros::WallTime& deadline) {
  constexpr double kSpin = 20e-6;  // [s] typical nanosleep wake-up latency with 1 ns timer slack
  const double left = (deadline - ros::WallTime::now()).toSec();
  if (left > kSpin) ros::WallDuration(left - kSpin).sleep();
  while (ros::WallTime::now() < deadline) std::this_thread::yield();
}

}  // namespace

nlohmann::json toJson(const LoadResult& r) {
  return {{"sent", r.sent},
          {"answered", r.answered},
          {"answers_lost", r.answers_lost},
          {"te_received", r.te_received},
          {"te_lost", r.te_lost},
          {"non_finite", r.non_finite},
          {"dropped_torque", r.dropped_torque},
          {"stiffness_shed", r.stiffness_shed},
          {"stiffness_coalesced", r.stiffness_coalesced},
          {"te_published", r.te_published},
          {"late_sends", r.late_sends},
          {"max_send_lateness_s", r.max_send_lateness_s},
          {"send_rate_hz", r.send_rate_hz},
          {"latency_p50_s", r.latency_p50_s},  // NaN (nothing measured) is written as null
          {"latency_p90_s", r.latency_p90_s},
          {"latency_p99_s", r.latency_p99_s},
          {"latency_max_s", r.latency_max_s},
          {"diagnostics_seen", r.diagnostics_seen},
          {"accepted_torque", r.accepted_torque},
          {"rejected_torque", r.rejected_torque},
          {"stiffness_published", r.stiffness_published},
          {"missed_deadlines", r.missed_deadlines},
          {"missed_deadlines_warmup", r.missed_deadlines_warmup},
          {"missed_deadlines_cpu", r.missed_deadlines_cpu},
          {"missed_deadlines_cpu_warmup", r.missed_deadlines_cpu_warmup},
          {"max_processing_cpu_s", r.max_processing_cpu_s},
          {"max_processing_cpu_topic", r.max_processing_cpu_topic},
          {"max_processing_s", r.max_processing_s},
          {"mean_processing_s", r.mean_processing_s},
          {"rss_warmup_kb", r.rss_warmup_kb},
          {"rss_end_kb", r.rss_end_kb},
          {"heap_end_b", r.heap_end_b},
          {"vibration_sent", r.vibration_sent},
          {"accepted_vibration", r.accepted_vibration},
          {"modal_published", r.modal_published}};
}

LoadGenerator::LoadGenerator(const ros::NodeHandle& nh, const LoadOptions& options)
    : options_(options), nh_(nh) {
  nh_.setCallbackQueue(&queue_);
  // Both queues hold every message of the run: a drop on our side (a slow callback thread, a
  // backed-up socket) would otherwise be blamed on the node.
  const double expected = (options_.rate_hz > 0.0 ? options_.rate_hz : 1e5) *
                          (options_.duration_s + options_.settle_timeout_s);
  const auto queue = static_cast<std::uint32_t>(std::clamp(expected, 1000.0, 1e8));
  torque_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>("torque", queue);
  if (options_.vibration_rate_hz > 0.0)
    vibration_pub_ = nh_.advertise<VibrationBlock>("vibration", 1000);
  stiffness_sub_ = nh_.subscribe("stiffness", queue, &LoadGenerator::onStiffness, this,
                                 ros::TransportHints().tcpNoDelay());
  te_sub_ = nh_.subscribe("transmission_error", queue, &LoadGenerator::onTransmissionError, this,
                          ros::TransportHints().tcpNoDelay());
  diagnostics_sub_ = nh_.subscribe("/diagnostics", 100, &LoadGenerator::onDiagnostics, this);
  spinner_ = std::make_unique<ros::AsyncSpinner>(1, &queue_);
  spinner_->start();
}

LoadGenerator::~LoadGenerator() {
  spinner_->stop();  // before the members its callbacks use go away
}

template <typename F>
bool LoadGenerator::waitFor(F done, double timeout_s) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (done()) return true;
    }
    if (ros::WallTime::now() > end) return false;
    ros::WallDuration(0.01).sleep();
  }
  return false;
}

bool LoadGenerator::connect() {
  // One diagnostics report proves the node is up and its counters are readable.
  const bool ok = waitFor(
      [this] {
        return torque_pub_.getNumSubscribers() > 0 && stiffness_sub_.getNumPublishers() > 0 &&
               diagnostics_received_ > 0 &&
               (!vibration_pub_ || vibration_pub_.getNumSubscribers() > 0);
      },
      options_.connect_timeout_s);
  // getNumPublishers() counts our stiffness link before the node has finished its handshake: an
  // answer sent meanwhile would be lost to us, not by the node.
  if (ok) ros::WallDuration(0.5).sleep();
  return ok;
}

void LoadGenerator::onStiffness(const Stiffness::ConstPtr& msg) {
  const ros::Time now = ros::Time::now();  // before the lock: its wait is not the node's latency
  bool finite = std::isfinite(msg->torque) && std::isfinite(msg->mesh_force) &&
                std::isfinite(msg->mesh_stiffness) && std::isfinite(msg->radial_stiffness_0) &&
                std::isfinite(msg->radial_stiffness_1);
  for (const auto& b : msg->bearings) finite = finite && std::isfinite(b.radial_stiffness);
  std::lock_guard<std::mutex> lock(mutex_);
  latencies_s_.push_back((now - msg->header.stamp).toSec());
  // Gaps after the first answer this generator saw (the node numbers from 0 over its lifetime).
  answers_lost_ += answer_gaps_.observe("stiffness", msg->header.seq);
  if (!finite) ++non_finite_;
}

void LoadGenerator::onTransmissionError(const TransmissionError::ConstPtr& msg) {
  const bool finite = std::isfinite(msg->dynamic_te) && std::isfinite(msg->static_te) &&
                      std::isfinite(msg->mesh_force);
  std::lock_guard<std::mutex> lock(mutex_);
  ++te_received_;
  te_lost_ += te_gaps_.observe("transmission_error", msg->header.seq);
  if (!finite) ++non_finite_;
}

void LoadGenerator::onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
  for (const auto& status : msg->status) {
    if (status.name != options_.diagnostic_status) continue;
    std::lock_guard<std::mutex> lock(mutex_);
    ++diagnostics_received_;
    diag_.diagnostics_seen = true;
    for (const auto& kv : status.values) {
      const char* v = kv.value.c_str();
      if (kv.key == "accepted_torque")
        diag_.accepted_torque = std::strtoull(v, nullptr, 10);
      else if (kv.key == "rejected_torque")
        diag_.rejected_torque = std::strtoull(v, nullptr, 10);
      else if (kv.key == "missed_deadlines")
        diag_.missed_deadlines = std::strtoull(v, nullptr, 10);
      else if (kv.key == "missed_deadlines_cpu")
        diag_.missed_deadlines_cpu = std::strtoull(v, nullptr, 10);
      else if (kv.key == "max_processing_cpu [s]")
        diag_.max_processing_cpu_s = std::strtod(v, nullptr);
      else if (kv.key == "max_processing_cpu_topic")
        diag_.max_processing_cpu_topic = kv.value;
      else if (kv.key == "stiffness_published")
        diag_.stiffness_published = std::strtoull(v, nullptr, 10);
      else if (kv.key == "dropped_torque")
        diag_.dropped_torque = std::strtoull(v, nullptr, 10);
      else if (kv.key == "stiffness_shed")
        diag_.stiffness_shed = std::strtoull(v, nullptr, 10);
      else if (kv.key == "stiffness_coalesced")
        diag_.stiffness_coalesced = std::strtoull(v, nullptr, 10);
      else if (kv.key == "transmission_error_published")
        diag_.te_published = std::strtoull(v, nullptr, 10);
      else if (kv.key == "max_processing [s]")
        diag_.max_processing_s = std::strtod(v, nullptr);
      else if (kv.key == "mean_processing [s]")
        diag_.mean_processing_s = std::strtod(v, nullptr);
      else if (kv.key == "resident_memory [kB]")
        diag_.rss_end_kb = std::strtod(v, nullptr);
      else if (kv.key == "heap_in_use [B]")
        diag_.heap_end_b = std::strtod(v, nullptr);
      else if (kv.key == "accepted_vibration")
        diag_.accepted_vibration = std::strtoull(v, nullptr, 10);
      else if (kv.key == "modal_identifications_published")
        diag_.modal_published = std::strtoull(v, nullptr, 10);
    }
    // The baseline: the first report after the warm-up (start-up allocations are done by then).
    const bool warm = !warmup_end_.isZero() && ros::WallTime::now() >= warmup_end_;
    if (warm && std::isnan(diag_.rss_warmup_kb)) {
      diag_.rss_warmup_kb = diag_.rss_end_kb;
      diag_.missed_deadlines_warmup = diag_.missed_deadlines;
      diag_.missed_deadlines_cpu_warmup = diag_.missed_deadlines_cpu;
    }
  }
}

LoadResult LoadGenerator::run() {
  const bool burst = options_.rate_hz <= 0.0;
  // A burst sends as many as 1e5 Hz would in duration_s, as fast as publish() returns.
  const auto total = static_cast<std::uint64_t>(
      std::llround((burst ? 1e5 : options_.rate_hz) * options_.duration_s));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    latencies_s_.clear();
    latencies_s_.reserve(total);  // no reallocation (and copy of up to MBs) inside the callback
  }
  // Linux lets a sleep overrun by the timer slack, 50 us by default: half a 10 kHz period.
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);

  LoadResult baseline;  // the node's counters before this run
  {
    std::lock_guard<std::mutex> lock(mutex_);
    baseline = diag_;
  }
  const LoadResult sends = send(total);
  settle(baseline, sends.sent);
  return collect(sends);
}

LoadResult LoadGenerator::send(std::uint64_t total) {
  const bool burst = options_.rate_hz <= 0.0;
  const double period = burst ? 0.0 : 1.0 / options_.rate_hz;  // [s]
  LoadResult r;
  geometry_msgs::WrenchStamped m;
  m.header.frame_id = "pinion";
  const ros::WallTime start = ros::WallTime::now();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    warmup_end_ = start + ros::WallDuration(options_.warmup_s);
  }
  ros::WallTime first_send, last_send;
  // The vibration blocks on their own schedule, stamped contiguously from the first send.
  VibrationBlock block;
  block.channels = {"pinion_bearing", "gear_bearing"};
  block.sample_rate = options_.vibration_rate_hz;
  block.data.resize(2 * static_cast<std::size_t>(options_.vibration_block));
  const double block_s = options_.vibration_block / std::max(options_.vibration_rate_hz, 1.0);
  std::mt19937 noise(1);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  const ros::Time vibration_t0 = ros::Time::now();
  std::uint64_t blocks = 0;
  for (std::uint64_t i = 0; i < total && ros::ok(); ++i) {
    // Absolute deadlines: a late send does not shift the ones after it (they catch up), so the
    // count and the mean rate are exact; lateness is counted instead.
    const double t = static_cast<double>(i) * (burst ? 1e-5 : period);  // [s] on the schedule
    const ros::WallTime deadline = start + ros::WallDuration(t);
    if (!burst) waitUntil(deadline);
    const ros::WallTime now = ros::WallTime::now();
    if (!burst) {
      const double lateness = (now - deadline).toSec();
      if (lateness > period) ++r.late_sends;  // its slot was missed
      r.max_send_lateness_s = std::max(r.max_send_lateness_s, lateness);
    }
    // roscpp numbers header.seq itself (per publication, gaps = losses); set it the same way
    // anyway.
    m.header.seq = next_seq_++;
    m.header.stamp = ros::Time::now();
    m.wrench.torque.z = options_.nominal_torque +
                        options_.ripple_torque * std::sin(kTwoPi * options_.ripple_hz * t);
    torque_pub_.publish(m);
    while (vibration_pub_ && static_cast<double>(blocks) * block_s <= t) {
      block.header.seq = static_cast<std::uint32_t>(blocks + 1);
      block.header.stamp = vibration_t0 + ros::Duration(static_cast<double>(blocks) * block_s);
      for (float& x : block.data) x = gauss(noise);
      vibration_pub_.publish(block);
      ++blocks;
    }
    r.vibration_sent = blocks;
    if (r.sent == 0) first_send = now;
    last_send = now;
    ++r.sent;
  }
  if (r.sent > 1)
    r.send_rate_hz = static_cast<double>(r.sent - 1) / (last_send - first_send).toSec();
  return r;
}

// Settles on the node's own counts, not on time: first until it has accounted for every input
// sent (accepted, rejected or seen dropped: the newest always arrives, as roscpp's queues drop
// the oldest), then until every answer it published has arrived or been seen missing. Both
// against its counters when this run started (they are totals since the node started).
void LoadGenerator::settle(const LoadResult& baseline, std::uint64_t sent) {
  const auto processed = [](const LoadResult& d) {
    return d.accepted_torque + d.rejected_torque + d.dropped_torque;
  };
  waitFor([&] { return processed(diag_) - processed(baseline) >= sent; },
          options_.settle_timeout_s);
  waitFor(
      [&] {
        return latencies_s_.size() + answers_lost_ >=
               diag_.stiffness_published - baseline.stiffness_published;
      },
      options_.settle_timeout_s);
  std::uint64_t reports = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    reports = diagnostics_received_;
  }
  waitFor([&] { return diagnostics_received_ >= reports + 2; }, options_.settle_timeout_s);
}

LoadResult LoadGenerator::collect(const LoadResult& sends) {
  std::vector<double> latencies;
  LoadResult r;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    latencies = latencies_s_;
    // The node's side (diag_) plus what this generator measured itself (sends and latency).
    r = diag_;
    r.sent = sends.sent;
    r.late_sends = sends.late_sends;
    r.max_send_lateness_s = sends.max_send_lateness_s;
    r.send_rate_hz = sends.send_rate_hz;
    r.answers_lost = answers_lost_;
    r.te_received = te_received_;
    r.te_lost = te_lost_;
    r.non_finite = non_finite_;
    r.vibration_sent = sends.vibration_sent;
  }
  r.answered = latencies.size();
  if (!latencies.empty()) {
    std::sort(latencies.begin(), latencies.end());
    r.latency_p50_s = percentile(latencies, 50.0);
    r.latency_p90_s = percentile(latencies, 90.0);
    r.latency_p99_s = percentile(latencies, 99.0);
    r.latency_max_s = latencies.back();
  }
  return r;
}

}  // namespace drivetrain_stiffness

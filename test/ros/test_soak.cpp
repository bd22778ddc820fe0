// Soak test of the stiffness_estimator node: ~duration [s] of torque at ~rate [Hz] (10 kHz, the
// seed rig's 0.1 N*m with a 100 Hz ripple). Every input must be accepted and answered, none may
// use more than the node's ~deadline of CPU time (and almost none of wall time), and the node's
// resident memory may not grow after the ~warmup [s] (no per-input leak or unbounded buffer).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "drivetrain_stiffness/ros/parameters.hpp"
#include "load_generator.hpp"

using namespace drivetrain_stiffness;

TEST(Soak, TenKilohertzTorqueForMinutes) {
  ros::NodeHandle pnh("~");
  LoadOptions options;
  options.rate_hz = readParam(pnh, "rate", 10000.0);
  options.duration_s = readParam(pnh, "duration", 180.0);
  options.warmup_s = readParam(pnh, "warmup", 30.0);
  ASSERT_LT(options.warmup_s, options.duration_s);

  LoadGenerator generator(ros::NodeHandle(), options);
  ASSERT_TRUE(generator.connect()) << "no stiffness_estimator on torque, stiffness and /diagnostics";
  const LoadResult r = generator.run();

  // rostest keeps the test's stdout in its log; ctest --output-on-failure shows the failure
  // messages: the trace puts the figures in each of them. The XML result gets them as properties.
  const nlohmann::json report = toJson(r);
  std::cout << "soak figures: " << report.dump() << std::endl;
  for (const auto& [key, value] : report.items()) RecordProperty(key, value.dump());
  SCOPED_TRACE("soak figures: " + report.dump());

  // The generator kept its rate, so the load is what this test claims. Its deadlines are absolute:
  // a late send is followed by a catch-up burst, so the count and the mean rate stay exact and the
  // node's task only gets harder. The generator shares the two cores with the node: on a machine
  // where a system call costs 1.1 us (`perf bench syscall basic`; nested virtualisation, 2026-11-22)
  // 3.3-3.6 % of its sends missed their 100 us slot (at most 10 ms late), against < 1 % on the
  // machine of the earlier runs (where rosbag::Bag::write, syscall-bound, was 6x faster). Bound the
  // bursts instead: at most 10 % late, none by more than 50 ms (500 inputs, half the node's
  // torque_queue_size, so the queue drops nothing).
  const auto expected = static_cast<std::uint64_t>(std::llround(options.rate_hz * options.duration_s));
  EXPECT_EQ(r.sent, expected);
  EXPECT_NEAR(r.send_rate_hz, options.rate_hz, 1e-3 * options.rate_hz);
  EXPECT_LE(r.late_sends, r.sent / 10) << "more than 10 % of the sends missed their slot";
  EXPECT_LT(r.max_send_lateness_s, 0.05) << "a send more than 50 ms late";

  ASSERT_TRUE(r.diagnostics_seen);
  EXPECT_EQ(r.accepted_torque, r.sent);
  EXPECT_EQ(r.rejected_torque, 0u);
  EXPECT_EQ(r.answered, r.sent) << "stiffness messages dropped";
  EXPECT_EQ(r.stiffness_published, r.sent);
  // The deadline, two ways. The node's own work (thread CPU time): the pipeline alone never exceeds
  // 0.07 ms on this load, yet in 3 runs of 1.8 M inputs 0-2 inputs used 1.0-1.2 ms of CPU time
  // (roscpp's queues and allocation; on this VM the thread clock may also count hypervisor
  // stalls), so allow 1e-5 of the inputs (18). Wall time adds preemption: 8-18 of 1.8 M inputs took
  // 1.8-5.9 ms on the earlier machine (the node's mean is 7-14 us), 83-170 where system calls cost
  // 1.1 us (the generator's and roscpp's threads then fill both cores); allow 1e-3 of the inputs.
  EXPECT_LE(r.missed_deadlines_cpu, r.sent / 100000)
      << "inputs whose processing used more than ~deadline of CPU time; max " << r.max_processing_cpu_s << " s";
  EXPECT_LE(r.missed_deadlines, r.sent / 1000) << "inputs that took longer than ~deadline of wall time ("
                                                << r.missed_deadlines_warmup << " of them in the warm-up); max "
                                                << r.max_processing_s << " s";
  ASSERT_FALSE(std::isnan(r.rss_warmup_kb) || std::isnan(r.rss_end_kb)) << "no memory report after the warm-up";
  EXPECT_LT(r.rss_end_kb - r.rss_warmup_kb, 2048.0) << "resident memory grew [kB]";
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "soak_rostest");
  return RUN_ALL_TESTS();
}

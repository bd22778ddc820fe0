// The ROS side of the per-input path: a Preload message converted into the caller's buffer
// (toPreloadSettings, as the node and the replay call it) and handed to a warmed-up RigPipeline
// allocates nothing in steady state. A counting global operator new (counting_new.cpp, this binary
// only) around the counted inputs; the warm-up is that of NoAllocation.PreloadInputsInSteadyState
// (test_no_allocation.cpp): 2 s of torque, then one pass of the preload cycle.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "counting_new.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "drivetrain_stiffness/ros/message_conversion.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;
using test::allocationCount;

namespace {

drivetrain_stiffness::Preload preloadMessage(const RigConfig& rig, double axial, double radial,
                                             double interference) {
  drivetrain_stiffness::Preload m;
  for (const BearingSupportConfig& b : rig.bearings) {
    drivetrain_stiffness::BearingPreload p;
    p.name = b.name;
    p.axial_preload = axial;
    p.radial_preload = radial;
    p.inner_interference = interference;
    p.outer_interference = interference;
    m.bearings.push_back(p);
  }
  return m;
}

}  // namespace

TEST(NoAllocation, PreloadMessagesConvertedIntoTheCallersBuffer) {
  const RigConfig& rig = test::seedServo();
  RigPipeline pipeline(rig, PipelineOptions{});
  PipelineSink sink;
  // Geometry changes (rebuilt supports), a radial change alone, and back to the file's values.
  const std::vector<drivetrain_stiffness::Preload> messages = {
      preloadMessage(rig, 1100.0, 1000.0, 5e-6), preloadMessage(rig, 1100.0, 1050.0, 5e-6),
      preloadMessage(rig, 1200.0, 950.0, 6e-6), preloadMessage(rig, 1000.0, 1000.0, 5e-6)};
  std::vector<PreloadSetting>
      buffer;  // the caller's, as StiffnessEstimatorRos and drivetrain_replay keep one
  std::size_t next = 0;
  auto step = [&](long k,
                  bool preloads) {  // k: 10 kHz ticks; a preload 50 us after every 500th torque
    const double t = 1e-4 * static_cast<double>(k);
    pipeline.torque(Stamp{test::kEpoch + 100000LL * k},
                    0.1 * (1.0 + 0.1 * std::sin(2.0 * M_PI * 100.0 * t)), sink);
    if (!preloads || k % 500 != 0) return;
    const drivetrain_stiffness::Preload& msg = messages[next];
    next = (next + 1) % messages.size();
    toPreloadSettings(msg, buffer);
    pipeline.preload(Stamp{test::kEpoch + 100000LL * k + 50000LL}, buffer,
                     sink);  // checked by the counters below
  };
  for (long k = 0; k < 20000; ++k) step(k, false);     // 2 s of torque
  for (long k = 20000; k < 22000; ++k) step(k, true);  // one pass of the cycle (4 preload inputs)
  const std::uint64_t accepted_before = pipeline.counters().accepted_preload;
  const long before = allocationCount();
  for (long k = 22000; k < 32000; ++k) step(k, true);  // 1 s: 20 preload inputs
  const long n = allocationCount() - before;
  EXPECT_EQ(n, 0) << n / 20.0
                  << " heap allocations per preload message (with 500 torque inputs each)";
  EXPECT_EQ(pipeline.counters().accepted_preload - accepted_before, 20u);
  EXPECT_EQ(pipeline.counters().rejected_preload, 0u) << pipeline.counters().last_event;
  // The conversion is the message's: every field, in order.
  const drivetrain_stiffness::Preload& last =
      messages[(next + messages.size() - 1) % messages.size()];
  ASSERT_EQ(buffer.size(), last.bearings.size());
  for (std::size_t i = 0; i < buffer.size(); ++i) {
    EXPECT_EQ(buffer[i].name, last.bearings[i].name);
    EXPECT_EQ(buffer[i].axial_preload, last.bearings[i].axial_preload);
    EXPECT_EQ(buffer[i].radial_preload, last.bearings[i].radial_preload);
    EXPECT_EQ(buffer[i].inner_interference, last.bearings[i].inner_interference);
    EXPECT_EQ(buffer[i].outer_interference, last.bearings[i].outer_interference);
  }
}

// The conversion alone, with names past the strings' small buffer (15 characters in libstdc++):
// after one message as large, the buffer's strings are reused.
TEST(NoAllocation, PreloadConversionReusesLongNames) {
  drivetrain_stiffness::Preload msg;
  for (const char* name : {"pinion_side_angular_contact_pair", "gear_side_angular_contact_pair"}) {
    drivetrain_stiffness::BearingPreload p;
    p.name = name;
    p.axial_preload = 1000.0;
    msg.bearings.push_back(p);
  }
  std::vector<PreloadSetting> buffer;
  toPreloadSettings(msg, buffer);  // sizes the buffer and its names
  const long before = allocationCount();
  for (int i = 0; i < 100; ++i) {
    msg.bearings[i % 2].axial_preload = 1000.0 + i;
    toPreloadSettings(msg, buffer);
  }
  EXPECT_EQ(allocationCount() - before, 0);
  EXPECT_EQ(buffer[1].name, "gear_side_angular_contact_pair");
  EXPECT_EQ(buffer[1].axial_preload, 1099.0);
}

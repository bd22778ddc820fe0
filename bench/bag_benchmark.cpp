// Bag output per message: rosbag::Bag::write against drivetrain_replay's BagWriter (which writes
// the same bytes, test/ros/test_bag_writer.cpp), LZ4 and uncompressed, for the two messages the
// replay writes at every 1 kHz input (Stiffness with two bearings, TransmissionError). The bag goes
// to /tmp; time includes the chunk compression and file writes, amortised (BagWriter does them on
// its worker thread, so its figure is the cost left on the analysis thread). Run:
// devel/lib/drivetrain_stiffness/bag_benchmark (figures: docs/performance.md, "Replay speed").
#include <benchmark/benchmark.h>

#include <rosbag/bag.h>

#include "bag/bag_writer.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/Stiffness.h"
#include "drivetrain_stiffness/TransmissionError.h"

namespace ds = drivetrain_stiffness;

namespace {

struct Messages {
  ds::Stiffness stiffness;
  ds::TransmissionError te;
  Messages() {
    stiffness.bearings.resize(2);
    stiffness.bearings[0].name = "pinion_support";
    stiffness.bearings[1].name = "gear_support";
  }
  /// Two messages at record time t (as the replay: one stiffness, one TE sample per input).
  template <typename Writer>
  void write(Writer& out, std::int64_t i) {
    const ros::Time t(1767225600 + i / 1000, static_cast<std::uint32_t>(i % 1000) * 1000000u);
    stiffness.header.stamp = te.header.stamp = t;
    stiffness.torque = te.torque = 10.0 + 1e-3 * static_cast<double>(i % 977);
    out.write("/stiffness", t, stiffness);
    out.write("/transmission_error", t, te);
  }
};

void BM_RosbagWrite(benchmark::State& state) {
  rosbag::Bag bag("/tmp/bag_benchmark_rosbag.bag", rosbag::bagmode::Write);
  bag.setCompression(state.range(0) ? rosbag::compression::LZ4 : rosbag::compression::Uncompressed);
  Messages m;
  std::int64_t i = 0;
  for (auto _ : state) m.write(bag, ++i);
  bag.close();
  state.SetItemsProcessed(2 * state.iterations());  // items = messages
}
BENCHMARK(BM_RosbagWrite)->Arg(1)->Arg(0)->ArgName("lz4")->Unit(benchmark::kMicrosecond);

void BM_BagWriterWrite(benchmark::State& state) {
  ds::BagWriter bag("/tmp/bag_benchmark_ours.bag",
                    state.range(0) ? ds::BagCompression::Lz4 : ds::BagCompression::None);
  Messages m;
  std::int64_t i = 0;
  for (auto _ : state) m.write(bag, ++i);
  bag.close();  // waits for the worker: its compression and writes are inside the measured time
  state.SetItemsProcessed(2 * state.iterations());
}
BENCHMARK(BM_BagWriterWrite)->Arg(1)->Arg(0)->ArgName("lz4")->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

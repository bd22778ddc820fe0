// BagWriter (drivetrain_replay's bag output) against rosbag::Bag, the reference writer of the ROS
// bag 2.0 format: for the same message stream both must write the same bytes, compressed (LZ4) and
// not, in one chunk and in many. rosbag::View must then read our bag back, by index, with the
// values written. Needs no master.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>

#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>

#include <geometry_msgs/WrenchStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include "bag/bag_writer.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/Stiffness.h"

namespace ds = drivetrain_stiffness;

namespace {

const ros::Time kStart(1767225600, 0);  // 2026-01-01, the scenario bags' epoch

ros::Time recordTime(int i) {
  ros::Time t = kStart + ros::Duration(i * 1e-3);
  if (i % 500 == 499) t = t - ros::Duration(0.5);  // out of order, as a looping or merged recording
  if (i % 97 == 0 && i > 0) t = recordTime(i - 1);  // equal record times
  return t;
}

/// 3000 messages on five topics of different types and sizes (variable-length arrays, strings with
/// '=', newline and NUL bytes, which the record header format must not confuse).
template <typename Writer>
std::map<std::string, int> writeStream(Writer& out) {
  std::map<std::string, int> counts;
  for (int i = 0; i < 3000; ++i) {
    const ros::Time t = recordTime(i);
    geometry_msgs::WrenchStamped torque;
    torque.header.stamp = t;
    torque.wrench.torque.z = 10.0 + 0.25 * i;
    out.write("/torque", t, torque);
    ++counts["/torque"];
    if (i % 2 == 0) {
      ds::Stiffness s;
      s.header.stamp = t;
      s.mesh_stiffness = 3.0e8 + i;
      s.bearings.resize(1 + i % 3);
      s.bearings.back().name = "support_" + std::to_string(i % 3);
      s.bearings.back().radial_stiffness = 1.0e8 * (1 + i % 5);
      out.write("/stiffness", t, s);
      ++counts["/stiffness"];
    }
    if (i % 10 == 0) {
      tf2_msgs::TFMessage tf;
      tf.transforms.resize(2);
      tf.transforms[0].header.stamp = t;
      tf.transforms[0].child_frame_id = "pinion";
      tf.transforms[1].child_frame_id = "gear";
      out.write("/tf", t, tf);
      ++counts["/tf"];
    }
    if (i % 7 == 0) {
      std_msgs::String text;
      text.data =
          "op=" + std::string(static_cast<std::size_t>(i % 300), 'x') + std::string("\n\0=", 3);
      out.write("/notes", t, text);
      ++counts["/notes"];
    }
    if (i == 2000) {
      std_msgs::String big;  // larger than the 4096-byte chunks: a chunk of its own, then a new one
      big.data = std::string(10000, 'b');
      out.write("/notes", t, big);
      ++counts["/notes"];
    }
    if (i == 1500) {
      geometry_msgs::WrenchStamped late;  // a topic first seen in a later chunk
      late.header.stamp = t;
      out.write("/late", t, late);
      ++counts["/late"];
    }
  }
  return counts;
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "bag_writer_" + name + ".bag";
}

struct Case {
  ds::BagCompression ours;
  rosbag::compression::CompressionType theirs;
  std::uint32_t chunk_bytes;
  const char* name;
};

class SameBytesAsRosbag : public ::testing::TestWithParam<Case> {};

TEST_P(SameBytesAsRosbag, ForTheSameStream) {
  const Case c = GetParam();
  const std::string reference = tempPath(std::string(c.name) + "_rosbag"),
                    ours = tempPath(std::string(c.name) + "_ours");
  {
    rosbag::Bag bag(reference, rosbag::bagmode::Write);
    bag.setCompression(c.theirs);
    bag.setChunkThreshold(c.chunk_bytes);
    writeStream(bag);
    bag.close();
  }
  ds::BagWriter writer(ours, c.ours, c.chunk_bytes);
  writeStream(writer);
  writer.close();
  const std::string expected = fileBytes(reference), got = fileBytes(ours);
  ASSERT_GT(expected.size(), 4117u);  // more than the version line and the 4 KiB header record
  EXPECT_EQ(got.size(), expected.size());
  EXPECT_TRUE(got == expected) << "bags differ: " << reference << " " << ours;
}

INSTANTIATE_TEST_SUITE_P(
    CompressionAndChunking, SameBytesAsRosbag,
    ::testing::Values(
        Case{ds::BagCompression::Lz4, rosbag::compression::LZ4, 768 * 1024, "lz4_one_chunk"},
        Case{ds::BagCompression::Lz4, rosbag::compression::LZ4, 4096, "lz4_many_chunks"},
        Case{ds::BagCompression::None, rosbag::compression::Uncompressed, 768 * 1024,
             "none_one_chunk"},
        Case{ds::BagCompression::None, rosbag::compression::Uncompressed, 4096,
             "none_many_chunks"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.name); });

TEST(BagWriter, ChunkSizeChangesTheFile) {  // so the many-chunk cases above test chunking
  ds::BagWriter one(tempPath("one"), ds::BagCompression::None),
      many(tempPath("many"), ds::BagCompression::None, 4096);
  writeStream(one);
  writeStream(many);
  one.close();
  many.close();
  EXPECT_NE(fileBytes(tempPath("one")), fileBytes(tempPath("many")));
}

TEST(BagWriter, RosbagViewReadsItBackByIndex) {
  const std::string path = tempPath("view");
  ds::BagWriter writer(path, ds::BagCompression::Lz4, 4096);
  const std::map<std::string, int> counts = writeStream(writer);
  writer.close();

  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<std::string, int> seen;
  ros::Time previous;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    ++seen[m.getTopic()];
    EXPECT_GE(m.getTime(), previous);  // the index orders records by time
    previous = m.getTime();
  }
  EXPECT_EQ(seen, counts);

  // A topic and time query answered from the index: the torque values written in [1.0 s, 2.0 s].
  const ros::Time from = kStart + ros::Duration(1.0), to = kStart + ros::Duration(2.0);
  std::map<double, int> expected_values, values;
  for (int i = 0; i < 3000; ++i) {
    if (recordTime(i) >= from && recordTime(i) <= to) ++expected_values[10.0 + 0.25 * i];
  }
  for (const rosbag::MessageInstance& m :
       rosbag::View(bag, rosbag::TopicQuery("/torque"), from, to)) {
    auto w = m.instantiate<geometry_msgs::WrenchStamped>();
    ASSERT_TRUE(w);
    EXPECT_EQ(w->header.stamp, m.getTime());
    ++values[w->wrench.torque.z];
  }
  EXPECT_EQ(values, expected_values);
  EXPECT_GT(values.size(), 900u);
}

TEST(BagWriter, EmptyBagIsTheSameAsRosbags) {
  {
    rosbag::Bag bag(tempPath("empty_rosbag"), rosbag::bagmode::Write);
    bag.close();
  }
  ds::BagWriter(tempPath("empty_ours"), ds::BagCompression::Lz4).close();
  EXPECT_EQ(fileBytes(tempPath("empty_ours")), fileBytes(tempPath("empty_rosbag")));
  rosbag::Bag bag(tempPath("empty_ours"), rosbag::bagmode::Read);
  EXPECT_EQ(rosbag::View(bag).size(), 0u);
}

template <typename E>
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "no error";
}

TEST(BagWriter, BadUseGetsAClearError) {
  ds::BagWriter writer(tempPath("errors"), ds::BagCompression::Lz4);
  geometry_msgs::WrenchStamped torque;
  std_msgs::String text;
  writer.write("/torque", kStart, torque);
  const std::string conflict =
      errorOf<std::invalid_argument>([&] { writer.write("/torque", kStart, text); });
  EXPECT_NE(conflict.find("'/torque'"), std::string::npos) << conflict;
  EXPECT_NE(conflict.find("geometry_msgs/WrenchStamped"), std::string::npos) << conflict;
  EXPECT_NE(conflict.find("std_msgs/String"), std::string::npos) << conflict;
  const std::string zero =
      errorOf<std::invalid_argument>([&] { writer.write("/torque", ros::Time(), torque); });
  EXPECT_NE(zero.find("time 0 on topic '/torque'"), std::string::npos) << zero;
  writer.close();
  EXPECT_NE(errorOf<std::logic_error>([&] {
              writer.write("/torque", kStart, torque);
            }).find("after close"),
            std::string::npos);

  const std::string missing = "/nonexistent_directory_for_bag_writer/out.bag";
  const std::string open_error =
      errorOf<std::runtime_error>([&] { ds::BagWriter w(missing, ds::BagCompression::None); });
  EXPECT_NE(open_error.find(missing), std::string::npos) << open_error;
  EXPECT_NE(errorOf<std::invalid_argument>([&] {
              ds::BagWriter w(tempPath("zero_chunk"), ds::BagCompression::None, 0);
            }).find("chunk size = 0"),
            std::string::npos);
}

// A refused write (time 0, here on a topic not seen before) changes nothing: rosbag checks the time
// before it makes a connection, so both bags must still be the same bytes.
TEST(BagWriter, RefusedWriteLeavesNoTrace) {
  const std::string ours = tempPath("refused_ours"), theirs = tempPath("refused_rosbag");
  {
    rosbag::Bag bag(theirs, rosbag::bagmode::Write);
    writeStream(bag);
    bag.close();
  }
  ds::BagWriter writer(ours, ds::BagCompression::None);
  std_msgs::String text;
  EXPECT_THROW(writer.write("/never_written", ros::Time(), text), std::invalid_argument);
  writeStream(writer);
  writer.close();
  EXPECT_TRUE(fileBytes(ours) == fileBytes(theirs)) << "a refused write left a connection behind";
}

// The worker's write error (the file-size limit here, as a full disk) reaches the writer at a later
// chunk hand-over; a caller that catches it and keeps writing (the replay's pipeline counts sink
// errors and goes on) must get errors, not undefined behaviour, and close() must name the path.
TEST(BagWriter, WritesAfterAWorkerErrorKeepFailingCleanly) {
  struct rlimit old_limit {};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  void (*old_handler)(int) = std::signal(SIGXFSZ, SIG_IGN);  // EFBIG from write(), not a signal
  struct rlimit limit = old_limit;
  limit.rlim_cur = 16 * 1024;  // room for the header and a few 4 KiB chunks
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  const std::string path = tempPath("fsize_limit");
  int errors = 0;
  std::string close_error;
  {
    ds::BagWriter writer(path, ds::BagCompression::None, 4096);
    geometry_msgs::WrenchStamped torque;
    for (int i = 0; i < 2000; ++i) {
      try {
        writer.write("/torque", recordTime(i), torque);
      } catch (const std::runtime_error& e) {
        ++errors;
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      }
    }
    close_error = errorOf<std::runtime_error>([&] { writer.close(); });
  }
  setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_GT(errors, 1) << "the error is reported again at every later hand-over";
  EXPECT_NE(close_error.find(path), std::string::npos) << close_error;
}

TEST(BagWriter, DiskFullIsReportedWithThePath) {
  // /dev/full accepts the open and fails every write with ENOSPC; the error must name the path
  // (from the constructor's header write, or from close() once a chunk is flushed).
  const std::string error = errorOf<std::runtime_error>([] {
    ds::BagWriter w("/dev/full", ds::BagCompression::None, 4096);
    writeStream(w);
    w.close();
  });
  EXPECT_NE(error.find("/dev/full"), std::string::npos) << error;
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

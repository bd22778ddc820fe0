// BagWriter: writes ROS bag format 2.0 (http://wiki.ros.org/Bags/Format/2.0) for
// drivetrain_replay's output streams, readable by rosbag::View, Python rosbag, `rosbag info/play`
// and rqt_bag.
//
// Why not rosbag::Bag::write: measured on this machine, it costs 1.6 us per message with LZ4 and
// 2.2 us uncompressed, in a bare loop outside our code. Its header template seeks to the end of the
// file before every record (fseeko -> fstat + lseek + read syscalls) and builds a std::map header
// per message. The replay writes two messages per 1 kHz input, so that alone caps it near 300x real
// time against the 500x target. Here a message is serialized straight into the chunk in memory
// (ros::serialization, the same bytes rosbag writes), and full chunks are compressed (roslz4, the
// library rosbag itself uses for "lz4" chunks) and written by one worker thread, in order, so the
// file is deterministic. The test (test/ros/test_bag_writer.cpp) reads our bags and rosbag::Bag's
// with rosbag::View and requires the same connections, times and message bytes.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <ros/time.h>

#include "ordered_worker.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {

namespace bag_records {
class Fields;
}

enum class BagCompression { None, Lz4 };

class BagWriter {
 public:
  /// Opens (truncates) `path`. A chunk is closed once its uncompressed data exceeds chunk_bytes
  /// (rosbag's rule and default, 768 KiB). Throws std::runtime_error naming the path if it cannot
  /// be written.
  BagWriter(const std::string& path, BagCompression compression,
            std::size_t chunk_bytes = 768 * 1024);
  ~BagWriter();  ///< closes the bag if close() was not called; errors there are printed, not thrown
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  /// One message record at record time `time` (must not be zero, as in rosbag). A topic keeps the
  /// type of its first message; another type on it is an error naming both.
  template <class M>
  void write(const std::string& topic, const ros::Time& time, const M& msg) {
    namespace mt = ros::message_traits;
    checkWritable(
        topic,
        time);  // before connection(): a refused write leaves no connection behind, as in rosbag
    const std::uint32_t conn =
        connection(topic, mt::datatype(msg), mt::md5sum(msg), mt::definition(msg));
    const std::uint32_t length = ros::serialization::serializationLength(msg);
    ros::serialization::OStream out(beginMessage(conn, time, length), length);
    ros::serialization::serialize(out, msg);
    endMessage();
  }

  /// Writes the last chunk, the index and the file header. Throws on an I/O error (naming the
  /// path).
  void close();

 private:
  struct Connection {
    std::string topic, datatype, md5sum, definition;
  };
  struct IndexEntry {
    std::uint32_t sec, nsec, offset;  ///< record time and offset in the uncompressed chunk
  };
  struct Chunk {
    std::vector<std::uint8_t> data;              ///< uncompressed records
    std::vector<std::vector<IndexEntry>> index;  ///< per connection id
    std::size_t messages = 0;
    ros::Time start, end;  ///< earliest and latest record time
  };
  struct ChunkInfo {
    std::uint64_t position;
    ros::Time start, end;
    struct Count {
      std::uint32_t connection, messages;
    };
    std::vector<Count> counts;
  };

  std::uint32_t connection(const std::string& topic, const char* datatype, const char* md5sum,
                           const char* definition);
  void checkWritable(const std::string& topic, const ros::Time& time) const;
  std::uint8_t* beginMessage(std::uint32_t conn, const ros::Time& time, std::uint32_t length);
  void endMessage();
  void handOver();                ///< queues the current chunk for the worker
  void writeChunk(Chunk& chunk);  ///< worker thread: compress, write chunk and index records
  bag_records::Fields chunkHeader(std::size_t uncompressed_size) const;
  void writeBytes(const void* data, std::size_t n);

  std::string path_;
  BagCompression compression_;
  std::size_t chunk_bytes_;
  std::FILE* file_ = nullptr;
  std::uint64_t position_ =
      0;  ///< file offset (worker thread once started; main thread after join)
  std::vector<Connection> connections_;
  std::vector<std::uint8_t> connection_records_;  ///< the index copy of each connection record
  Chunk chunk_;
  std::vector<ChunkInfo> chunk_infos_;  ///< written by the worker, read after join
  std::vector<char> compressed_;        ///< worker's buffer
  bool closed_ = false;
  OrderedWorker<Chunk> worker_;  ///< last: its thread uses the members above
};

}  // namespace drivetrain_stiffness

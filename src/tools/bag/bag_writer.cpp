#include "bag_writer.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <stdexcept>

#include <roslz4/lz4s.h>

// Record layout, ROS bag format 2.0 (http://wiki.ros.org/Bags/Format/2.0, "Records" and "Op
// codes"):
//   <header_len u32><header><data_len u32><data>, header = repeated <field_len u32><name>=<value>,
// integers little-endian, times as <sec u32><nsec u32>.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "bag records are little-endian; this writer copies host integers");

namespace drivetrain_stiffness {
namespace bag_records {  // record encoding, used only in this file

constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
constexpr std::size_t kVersionLineLength = sizeof kVersionLine - 1;
// Bag header record: header plus ' ' padding is 4096 bytes, so the header can be rewritten in place
// on close (format 2.0, "Bag header"; rosbag's FILE_HEADER_LENGTH).
constexpr std::uint32_t kFileHeaderLength = 4096;
// rosbag's LZ4Stream uses block size id 6; roslz4 is the library behind its "lz4" chunks.
constexpr int kLz4BlockSizeId = 6;

enum Op : std::uint8_t {
  kMessageData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07
};

void append(std::vector<std::uint8_t>& out, const void* data, std::size_t n) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  out.insert(out.end(), p, p + n);
}

template <typename T>
void appendValue(std::vector<std::uint8_t>& out, T value) {
  append(out, &value, sizeof value);
}

/// A record header (or a connection header): <len><name>=<value> fields.
class Fields {
 public:
  Fields& bytes(const char* name, const void* value, std::size_t n) {
    const std::size_t name_length = std::strlen(name);
    appendValue(out_, static_cast<std::uint32_t>(name_length + 1 + n));
    append(out_, name, name_length);
    out_.push_back('=');
    append(out_, value, n);
    return *this;
  }
  Fields& op(Op op) { return bytes("op", &op, 1); }
  Fields& u32(const char* name, std::uint32_t v) { return bytes(name, &v, sizeof v); }
  Fields& u64(const char* name, std::uint64_t v) { return bytes(name, &v, sizeof v); }
  Fields& time(const char* name, const ros::Time& t) {
    const std::uint32_t v[2] = {t.sec, t.nsec};
    return bytes(name, v, sizeof v);
  }
  Fields& text(const char* name, const std::string& s) { return bytes(name, s.data(), s.size()); }
  const std::vector<std::uint8_t>& data() const { return out_; }

 private:
  std::vector<std::uint8_t> out_;
};

/// <header_len><header><data_len><data>
void appendRecord(std::vector<std::uint8_t>& out, const Fields& header, const void* data,
                  std::size_t n) {
  appendValue(out, static_cast<std::uint32_t>(header.data().size()));
  append(out, header.data().data(), header.data().size());
  appendValue(out, static_cast<std::uint32_t>(n));
  append(out, data, n);
}

// A message data record's header, field by field as rosbag writes it (conn, op, time):
// 4+5+4 ("conn=" u32) + 4+3+1 ("op=" u8) + 4+5+8 ("time=" sec, nsec) = 38 bytes.
constexpr std::uint32_t kMessageHeaderLength = 38;
constexpr std::size_t kMessagePrefix = 4 + kMessageHeaderLength + 4;

std::uint8_t* put(std::uint8_t* p, const void* data, std::size_t n) {
  std::memcpy(p, data, n);
  return p + n;
}
std::uint8_t* putU32(std::uint8_t* p, std::uint32_t v) { return put(p, &v, sizeof v); }

}  // namespace bag_records

using namespace bag_records;  // NOLINT(build/namespaces)

BagWriter::BagWriter(const std::string& path, BagCompression compression, std::size_t chunk_bytes)
    : path_(path),
      compression_(compression),
      chunk_bytes_(chunk_bytes),
      worker_([this](Chunk& c) { writeChunk(c); }) {
  if (chunk_bytes_ == 0 || chunk_bytes_ > (1u << 30)) {
    throw std::invalid_argument("BagWriter: chunk size = " + std::to_string(chunk_bytes) +
                                " bytes, must be in (0, 1 GiB]");
  }
  static_assert(sizeof(IndexEntry) == 12 && sizeof(ChunkInfo::Count) == 8,
                "index entries are packed u32 fields");
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) throw std::runtime_error("cannot write bag '" + path_ + "': " + std::strerror(errno));
  struct CloseOnThrow {  // the destructor does not run if the constructor throws
    std::FILE*& file;
    bool armed = true;
    ~CloseOnThrow() {
      if (armed) std::fclose(file);
    }
  } guard{file_};
  writeBytes(kVersionLine, kVersionLineLength);
  // Placeholder of the final header's exact size (all its fields are fixed-width); rewritten by
  // close().
  Fields header;
  header.u32("chunk_count", 0).u32("conn_count", 0).u64("index_pos", 0).op(kBagHeader);
  std::vector<std::uint8_t> record;
  const std::string padding(kFileHeaderLength - header.data().size(), ' ');
  appendRecord(record, header, padding.data(), padding.size());
  writeBytes(record.data(), record.size());
  chunk_.data.reserve(chunk_bytes_ + 64 * 1024);
  guard.armed = false;
}

BagWriter::~BagWriter() {
  try {
    close();
  } catch (const std::exception& e) {
    std::cerr << "BagWriter: " << e.what() << "\n";
  }
}

std::uint32_t BagWriter::connection(const std::string& topic, const char* datatype,
                                    const char* md5sum, const char* definition) {
  for (std::size_t id = 0; id < connections_.size(); ++id) {
    const Connection& c = connections_[id];
    if (c.topic != topic) continue;
    if (c.datatype != datatype) {
      throw std::invalid_argument("BagWriter: topic '" + topic + "' has type " + c.datatype +
                                  ", not " + datatype);
    }
    return static_cast<std::uint32_t>(id);
  }
  const auto id = static_cast<std::uint32_t>(connections_.size());
  connections_.push_back({topic, datatype, md5sum, definition});
  // Connection record (op 0x07): in the chunk where the topic first appears, as rosbag writes it,
  // and again in the index section after the chunks, where readers look for it. Its data is the
  // connection header rosbag::Bag::write makes: md5sum, message_definition, type.
  Fields header, connection_header;
  header.u32("conn", id).op(kConnection).text("topic", topic);
  connection_header.text("md5sum", md5sum)
      .text("message_definition", definition)
      .text("type", datatype);
  appendRecord(chunk_.data, header, connection_header.data().data(),
               connection_header.data().size());
  appendRecord(connection_records_, header, connection_header.data().data(),
               connection_header.data().size());
  chunk_.index.resize(connections_.size());
  return id;
}

void BagWriter::checkWritable(const std::string& topic, const ros::Time& time) const {
  if (closed_) throw std::logic_error("BagWriter: write after close of '" + path_ + "'");
  if (time.isZero())
    throw std::invalid_argument("BagWriter: record time 0 on topic '" + topic +
                                "' (a bag needs time > 0)");
}

std::uint8_t* BagWriter::beginMessage(std::uint32_t conn, const ros::Time& time,
                                      std::uint32_t length) {
  Chunk& c = chunk_;
  if (c.messages++ == 0) {
    c.start = c.end = time;
  } else {
    c.start = std::min(c.start, time);
    c.end = std::max(c.end, time);
  }
  const std::size_t offset = c.data.size();
  c.index[conn].push_back({time.sec, time.nsec, static_cast<std::uint32_t>(offset)});
  c.data.resize(offset + kMessagePrefix + length);
  std::uint8_t* p = c.data.data() + offset;
  const Op op = kMessageData;
  const std::uint32_t stamp[2] = {time.sec, time.nsec};
  p = putU32(p, kMessageHeaderLength);
  p = put(putU32(p, 5 + 4), "conn=", 5);
  p = putU32(p, conn);
  p = put(putU32(p, 3 + 1), "op=", 3);
  p = put(p, &op, 1);
  p = put(putU32(p, 5 + 8), "time=", 5);
  p = put(p, stamp, sizeof stamp);
  return putU32(p, length);
}

void BagWriter::endMessage() {
  // rosbag closes a chunk once its uncompressed data exceeds the threshold (Bag::getChunkOffset);
  // the same rule gives the same chunks, and so the same file.
  if (chunk_.data.size() > chunk_bytes_) handOver();
}

void BagWriter::handOver() {
  // The next chunk is set up before submit(), which rethrows an earlier write error of the worker:
  // a caller that catches it and writes on must find a valid (empty) chunk, not a moved-from one.
  Chunk full = std::move(chunk_);
  chunk_ = Chunk{};
  chunk_.data.reserve(chunk_bytes_ + 64 * 1024);
  chunk_.index.resize(connections_.size());
  worker_.submit(std::move(full));
}

void BagWriter::writeChunk(Chunk& chunk) {
  const std::uint64_t chunk_position = position_;
  const void* payload = chunk.data.data();
  std::size_t payload_size = chunk.data.size();
  if (compression_ == BagCompression::Lz4) {
    std::size_t capacity = payload_size + payload_size / 16 + 4096;
    for (;;) {
      compressed_.resize(capacity);
      auto out_size = static_cast<unsigned int>(capacity);
      const int rc = roslz4_buffToBuffCompress(reinterpret_cast<char*>(chunk.data.data()),
                                               static_cast<unsigned int>(chunk.data.size()),
                                               compressed_.data(), &out_size, kLz4BlockSizeId);
      if (rc == ROSLZ4_OUTPUT_SMALL) {
        capacity *= 2;
        continue;
      }
      if (rc != ROSLZ4_OK)
        throw std::runtime_error("LZ4 compression failed (roslz4 code " + std::to_string(rc) +
                                 ") for '" + path_ + "'");
      payload = compressed_.data();
      payload_size = out_size;
      break;
    }
  }
  std::vector<std::uint8_t> records;
  appendRecord(records, chunkHeader(chunk.data.size()), payload, payload_size);
  // One index data record (op 0x04, version 1) per connection present in the chunk, right after it.
  ChunkInfo info{chunk_position, chunk.start, chunk.end, {}};
  for (std::size_t id = 0; id < chunk.index.size(); ++id) {
    std::vector<IndexEntry>& entries = chunk.index[id];
    if (entries.empty()) continue;
    // Entries in record-time order, equal times in write order: rosbag keeps them in a multiset
    // ordered by time, which readers rely on to merge chunks in time order.
    std::stable_sort(entries.begin(), entries.end(), [](const IndexEntry& a, const IndexEntry& b) {
      return a.sec != b.sec ? a.sec < b.sec : a.nsec < b.nsec;
    });
    const auto count = static_cast<std::uint32_t>(entries.size());
    Fields index_header;
    index_header.u32("conn", static_cast<std::uint32_t>(id))
        .u32("count", count)
        .op(kIndexData)
        .u32("ver", 1);
    appendRecord(records, index_header, entries.data(), entries.size() * sizeof(IndexEntry));
    info.counts.push_back({static_cast<std::uint32_t>(id), count});
  }
  writeBytes(records.data(), records.size());
  chunk_infos_.push_back(std::move(info));
}

Fields BagWriter::chunkHeader(std::size_t uncompressed_size) const {
  Fields header;
  header.text("compression", compression_ == BagCompression::Lz4 ? "lz4" : "none")
      .op(kChunk)
      .u32("size", static_cast<std::uint32_t>(uncompressed_size));
  return header;
}

void BagWriter::writeBytes(const void* data, std::size_t n) {
  if (std::fwrite(data, 1, n, file_) != n) {
    throw std::runtime_error("cannot write bag '" + path_ + "': " + std::strerror(errno));
  }
  position_ += n;
}

void BagWriter::close() {
  if (closed_) return;
  closed_ = true;
  std::exception_ptr error = worker_.flushAndFinish([this] {
    if (chunk_.messages > 0) handOver();
  });
  if (!error) {
    try {
      // Index section (format 2.0, "Bag header": index_pos): every connection record, then one
      // chunk info record (op 0x06, version 1) per chunk; then the header is rewritten with the
      // counts.
      const std::uint64_t index_position = position_;
      std::vector<std::uint8_t> index = connection_records_;
      for (const ChunkInfo& info : chunk_infos_) {
        Fields header;
        header.u64("chunk_pos", info.position)
            .u32("count", static_cast<std::uint32_t>(info.counts.size()))
            .time("end_time", info.end)
            .op(kChunkInfo)
            .time("start_time", info.start)
            .u32("ver", 1);
        appendRecord(index, header, info.counts.data(),
                     info.counts.size() * sizeof(ChunkInfo::Count));
      }
      writeBytes(index.data(), index.size());
      Fields header;
      header.u32("chunk_count", static_cast<std::uint32_t>(chunk_infos_.size()))
          .u32("conn_count", static_cast<std::uint32_t>(connections_.size()))
          .u64("index_pos", index_position)
          .op(kBagHeader);
      std::vector<std::uint8_t> record;
      const std::string padding(kFileHeaderLength - header.data().size(), ' ');
      appendRecord(record, header, padding.data(), padding.size());
      if (std::fseek(file_, static_cast<long>(kVersionLineLength), SEEK_SET) != 0) {
        throw std::runtime_error("cannot seek in bag '" + path_ + "': " + std::strerror(errno));
      }
      writeBytes(record.data(), record.size());
    } catch (...) {
      error = std::current_exception();
    }
  }
  if (std::fclose(file_) != 0 && !error) {
    error = std::make_exception_ptr(
        std::runtime_error("cannot close bag '" + path_ + "': " + std::strerror(errno)));
  }
  file_ = nullptr;
  if (error) std::rethrow_exception(error);
}

}  // namespace drivetrain_stiffness

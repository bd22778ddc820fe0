#include "bag_sequential_reader.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>
#include <vector>

#include "bag_records.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

using bag::ChunkRecord;
using bag::Fields;
using bag::fixedField;
using bag::kVersionLine;
using bag::kVersionLineLength;
using bag::opName;
using bag::parseChunkRecord;
using bag::parseFields;
using namespace bag;  // op codes

std::string str(std::uint64_t n) { return std::to_string(n); }

/// A connection record's fields and connection header. Returns what is wrong, or "".
std::string parseConnection(const Fields& fields, const std::uint8_t* data, std::size_t n,
                            std::map<std::uint32_t, BagConnection>& connections) {
  std::uint32_t id = 0;
  const auto topic = fields.find("topic");
  if (!fixedField(fields, "conn", id) || topic == fields.end())
    return "connection record without 'conn' and 'topic' fields";
  BagConnection connection;
  connection.topic = topic->second;
  const std::string error = parseFields(data, n, connection.header);
  if (!error.empty()) return "connection header: " + error;
  connections.try_emplace(
      id, std::move(connection));  // rosbag writes each twice: in a chunk and at the end
  return "";
}

}  // namespace

std::string BagDamage::describe(const std::string& file) const {
  return "'" + file + "' at byte " + std::to_string(offset) + ": " + what;
}

std::string BagConnection::field(const std::string& name) const {
  const auto it = header.find(name);
  return it == header.end() ? std::string() : it->second;
}

SequentialBagReader::SequentialBagReader(const std::string& path) : file_(path) {
  char line[kVersionLineLength];
  if (file_.size() < kVersionLineLength || !file_.readAt(0, line, kVersionLineLength) ||
      std::memcmp(line, kVersionLine, kVersionLineLength) != 0) {
    throw InvalidInput("'" + path +
                       "': not a ROS bag of format 2.0 (it does not start with '#ROSBAG V2.0')");
  }
  position_ = kVersionLineLength;
  readFileHeader();  // a damaged bag header is damage (next() returns false), not a refusal
}

bool SequentialBagReader::next(BagRecordMessage& message) {
  while (!damage_) {
    if (chunk_next_ < chunk_size_ || !chunk_short_.empty()) {
      if (nextInChunk(message)) return true;
      if (damage_) break;
    }
    if (!loadNextChunk()) break;
  }
  return false;
}

bool SequentialBagReader::readFileHeader() {
  Record r;
  if (!readRecord(position_, r)) return false;
  if (r.op != kBagHeader)
    return fail(r.offset, "the first record is not the bag header (op " + opName(r.op) + ")");
  if (!fixedField(r.fields, "index_pos", index_position_) ||
      !fixedField(r.fields, "chunk_count", chunk_count_)) {
    return fail(r.offset, "bag header without 'index_pos' and 'chunk_count' fields");
  }
  const auto encryptor = r.fields.find("encryptor");
  if (encryptor != r.fields.end() && !encryptor->second.empty()) {
    return fail(r.offset, "encrypted bag (encryptor '" + encryptor->second +
                              "'): its chunks cannot be read without rosbag");
  }
  position_ = r.data_offset + r.data_length;
  return true;
}

/// Reads top-level records up to the next chunk and loads it; false at the end of the file or
/// damage.
bool SequentialBagReader::loadNextChunk() {
  chunk_size_ = chunk_next_ = 0;
  while (position_ < file_.size()) {
    Record r;
    if (!readRecord(position_, r)) return false;
    position_ = r.data_offset + r.data_length;
    switch (r.op) {
      case kChunk: return loadChunk(r);
      case kConnection:  // the copies at the end of a closed bag
        if (!readTopLevelConnection(r)) return false;
        break;
      case kChunkInfo: ++chunk_infos_read_; break;
      case kIndexData: break;
      default:
        return fail(r.offset, "record op " + opName(r.op) +
                                  " where a chunk, index or connection record belongs");
    }
  }
  return atEndOfFile();
}

bool SequentialBagReader::loadChunk(const Record& chunk) {
  std::uint32_t size = 0;
  const auto compression = chunk.fields.find("compression");
  if (compression == chunk.fields.end() || !fixedField(chunk.fields, "size", size)) {
    return fail(chunk.offset, "chunk header without 'compression' and 'size' fields");
  }
  chunk_offset_ = chunk.offset;
  chunk_data_offset_ = chunk.data_offset;
  chunk_compressed_ = compression->second != "none";
  chunk_short_.clear();
  std::uint64_t present =
      std::min<std::uint64_t>(chunk.data_length, file_.size() - chunk.data_offset);
  if (chunk.data_length == 0 && size == 0) {
    // rosbag writes zero sizes when it opens a chunk and the real ones when it closes it: this one
    // was never closed (the recording stopped). Its records run to the end of the file.
    if (chunk_compressed_) {
      return fail(chunk.offset, "this " + compression->second +
                                    " chunk was never finished (a recording cut short): compressed "
                                    "data cannot be read without its size");
    }
    present = file_.size() - chunk.data_offset;
    position_ = file_.size();
    chunk_short_ =
        "the chunk at byte " + str(chunk.offset) + " was never finished (a recording cut short)";
  } else if (present < chunk.data_length) {
    chunk_short_ = "truncated: the file ends at byte " + str(file_.size()) +
                   ", inside the chunk at byte " + str(chunk.offset) + " (" + str(present) +
                   " of its " + str(chunk.data_length) + " bytes present)";
    if (chunk_compressed_)
      return fail(chunk.offset,
                  chunk_short_ + "; a compressed chunk is read whole: its messages are lost");
  } else if (!chunk_compressed_ && size != chunk.data_length) {
    return fail(chunk.offset, "uncompressed chunk whose size field (" + str(size) +
                                  ") differs from its data length (" + str(chunk.data_length) +
                                  ")");
  }
  if (chunk_compressed_) return decompress(compression->second, chunk, size);
  chunk_ = readData(chunk.data_offset, present);
  if (!chunk_) return false;
  chunk_size_ = present;
  return true;
}

bool SequentialBagReader::decompress(const std::string& compression, const Record& chunk,
                                     std::uint32_t size) {
  const std::unique_ptr<std::uint8_t[]> in = readData(chunk.data_offset, chunk.data_length);
  if (!in) return false;
  const std::string error = decompressChunk(compression, in.get(), chunk.data_length, size, chunk_);
  if (!error.empty()) return fail(chunk.offset, error);
  chunk_size_ = size;
  return true;
}

bool SequentialBagReader::nextInChunk(BagRecordMessage& message) {
  while (chunk_next_ < chunk_size_) {
    const std::size_t at = chunk_next_;
    ChunkRecord r;
    bool cut_off = false;
    const std::string error = parseChunkRecord(chunk_.get() + at, chunk_size_ - at, r, cut_off);
    if (!error.empty())
      return failInChunk(at, cut_off && !chunk_short_.empty()
                                 ? chunk_short_ + "; this record is cut off"
                                 : "damaged record: " + error);
    chunk_next_ = at + r.length;
    if (r.op == kConnection) {
      const std::string bad = parseConnection(r.fields, r.data, r.data_length, connections_);
      if (!bad.empty()) return failInChunk(at, bad);
      continue;
    }
    std::uint32_t id = 0, time[2] = {0, 0};
    if (r.op != kMessageData)
      return failInChunk(at, "record op " + opName(r.op) +
                                 " inside a chunk (only messages and connections belong there)");
    if (!fixedField(r.fields, "conn", id) || !fixedField(r.fields, "time", time))
      return failInChunk(at, "message record without 'conn' and 'time' fields");
    const auto connection = connections_.find(id);
    if (connection == connections_.end())
      return failInChunk(at, "message on connection " + str(id) +
                                 ", which no connection record before it defines");
    ++connection->second.messages;
    message.connection = &connection->second;
    message.time.sec = time[0];  // as rosbag reads it: no normalization
    message.time.nsec = time[1];
    message.data = r.data;
    message.size = r.data_length;
    message.offset = chunk_compressed_ ? chunk_offset_ : chunk_data_offset_ + at;
    return true;
  }
  if (!chunk_short_.empty())
    return fail(chunk_data_offset_ + chunk_size_,
                chunk_short_ + "; it ends after its last whole record");
  return false;
}

bool SequentialBagReader::readTopLevelConnection(const Record& record) {
  const std::unique_ptr<std::uint8_t[]> data = readData(record.data_offset, record.data_length);
  if (!data) return false;
  const std::string error =
      parseConnection(record.fields, data.get(), record.data_length, connections_);
  return error.empty() || fail(record.offset, error);
}

/// At the end of the file between records: whole if the index was all there, else damage.
bool SequentialBagReader::atEndOfFile() {
  const std::string ends = "the file ends at byte " + str(file_.size());
  if (index_position_ == 0) {
    return fail(
        file_.size(),
        "the bag was never closed (its header has no index position: a recording cut short); " +
            ends + ", after its last whole record");
  }
  if (file_.size() < index_position_) {
    return fail(file_.size(), "truncated: " + ends + ", before the end of its chunks at byte " +
                                  str(index_position_) + " (bag header)");
  }
  if (file_.size() == index_position_ && chunk_count_ > 0) {
    return fail(
        file_.size(),
        "truncated: " + ends + ", where its index should begin (bag header): the index is missing");
  }
  if (chunk_infos_read_ < chunk_count_) {
    return fail(file_.size(), "truncated: " + ends + " inside its index (from byte " +
                                  str(index_position_) + "): " + str(chunk_infos_read_) +
                                  " of its " + str(chunk_count_) + " chunk info records present");
  }
  return false;
}

bool SequentialBagReader::readRecord(std::uint64_t offset, Record& r) {
  const std::string error = file_.readRecord(offset, r);
  return error.empty() || fail(offset, error);
}

std::unique_ptr<std::uint8_t[]> SequentialBagReader::readData(std::uint64_t offset, std::size_t n) {
  std::string error;
  std::unique_ptr<std::uint8_t[]> data = file_.readData(offset, n, error);
  if (!data) fail(offset, error);
  return data;
}

bool SequentialBagReader::fail(std::uint64_t offset, const std::string& what) {
  if (!damage_) damage_ = BagDamage{offset, what};
  chunk_size_ = chunk_next_ = 0;
  chunk_short_.clear();
  return false;
}

/// Uncompressed chunks: the record's own offset in the file; compressed: the chunk's, plus where in
/// its uncompressed data.
bool SequentialBagReader::failInChunk(std::size_t at, const std::string& what) {
  if (chunk_compressed_)
    return fail(chunk_offset_,
                what + " (at byte " + str(at) + " of this chunk's uncompressed data)");
  return fail(chunk_data_offset_ + at,
              what + " (a record of the chunk at byte " + str(chunk_offset_) + ")");
}

}  // namespace drivetrain_stiffness

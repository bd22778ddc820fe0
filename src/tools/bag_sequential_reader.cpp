#include "bag_sequential_reader.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>
#include <vector>

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include "drivetrain_stiffness/core/validation.hpp"

// Record layout, ROS bag format 2.0 (http://wiki.ros.org/Bags/Format/2.0, "Records" and "Op codes"):
//   <header_len u32><header><data_len u32><data>, header = repeated <field_len u32><name>=<value>,
// integers little-endian, times as <sec u32><nsec u32>. The bag header record follows the version
// line; chunks (compression "none", "lz4" or "bz2") hold connection and message records, each chunk
// followed by its index data records; at index_pos (bag header) the connection and chunk info
// records end the file.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "bag records are little-endian; this reader copies host integers");

namespace drivetrain_stiffness {
namespace {

constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
constexpr std::size_t kVersionLineLength = sizeof kVersionLine - 1;
enum Op : std::uint8_t { kMessageData = 0x02, kBagHeader = 0x03, kIndexData = 0x04, kChunk = 0x05, kChunkInfo = 0x06,
                         kConnection = 0x07 };
using Fields = std::map<std::string, std::string>;

std::uint32_t u32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

std::string str(std::uint64_t n) { return std::to_string(n); }

std::string opName(std::uint8_t op) {
  char s[8];
  std::snprintf(s, sizeof s, "0x%02x", op);
  return s;
}

/// Parses <len u32><name>=<value> fields filling [p, p + n) exactly (a record header or a connection
/// header). Returns what is wrong, or "".
std::string parseFields(const std::uint8_t* p, std::size_t n, Fields& fields) {
  for (std::size_t i = 0; i < n;) {
    if (n - i < 4) return "header ends inside a field length";
    const std::uint32_t length = u32(p + i);
    i += 4;
    if (length > n - i) return "header field of " + str(length) + " bytes runs past the header's end (" + str(n - i) + " left)";
    const auto* begin = reinterpret_cast<const char*>(p + i);
    const auto* equals = static_cast<const char*>(std::memchr(begin, '=', length));
    if (!equals) return "header field without '='";
    fields[std::string(begin, equals)] = std::string(equals + 1, begin + length);
    i += length;
  }
  return "";
}

/// A fixed-size binary field (integers, times); false if absent or of another size.
template <typename T>
bool fixedField(const Fields& fields, const char* name, T& value) {
  const auto it = fields.find(name);
  if (it == fields.end() || it->second.size() != sizeof(T)) return false;
  std::memcpy(&value, it->second.data(), sizeof(T));
  return true;
}

/// A record inside a chunk's uncompressed data.
struct ChunkRecord {
  Fields fields;
  std::uint8_t op = 0;
  const std::uint8_t* data = nullptr;
  std::uint32_t data_length = 0;
  std::size_t length = 0;
};

/// Parses the record at the start of [p, p + n). Returns what is wrong, or ""; `cut_off` says the
/// record needs bytes beyond n (the end of a truncated chunk, or a damaged length).
std::string parseChunkRecord(const std::uint8_t* p, std::size_t n, ChunkRecord& r, bool& cut_off) {
  cut_off = true;
  if (n < 4) return "record cut off inside its header length (" + str(n) + " of 4 bytes)";
  const std::uint32_t header_length = u32(p);
  if (n - 4 < header_length + std::size_t{4}) return "record header of " + str(header_length) + " bytes runs past the chunk's end (" + str(n - 4) + " bytes left)";
  r.data_length = u32(p + 4 + header_length);
  const std::size_t data_begin = 8 + std::size_t{header_length};
  if (r.data_length > n - data_begin) return "record data of " + str(r.data_length) + " bytes runs past the chunk's end (" + str(n - data_begin) + " bytes left)";
  cut_off = false;
  r.fields.clear();
  const std::string error = parseFields(p + 4, header_length, r.fields);
  if (!error.empty()) return error;
  if (!fixedField(r.fields, "op", r.op)) return "record header without a one-byte 'op' field";
  r.data = p + data_begin;
  r.length = data_begin + r.data_length;
  return "";
}

/// A connection record's fields and connection header. Returns what is wrong, or "".
std::string parseConnection(const Fields& fields, const std::uint8_t* data, std::size_t n,
                            std::map<std::uint32_t, BagConnection>& connections) {
  std::uint32_t id = 0;
  const auto topic = fields.find("topic");
  if (!fixedField(fields, "conn", id) || topic == fields.end()) return "connection record without 'conn' and 'topic' fields";
  BagConnection connection;
  connection.topic = topic->second;
  const std::string error = parseFields(data, n, connection.header);
  if (!error.empty()) return "connection header: " + error;
  connections.try_emplace(id, std::move(connection));  // rosbag writes each twice: in a chunk and at the end
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

/// A top-level record: its header, and where its data is (read separately, only when needed).
struct SequentialBagReader::Record {
  std::uint64_t offset = 0;
  Fields fields;
  std::uint8_t op = 0;
  std::uint64_t data_offset = 0;
  std::uint32_t data_length = 0;
};

SequentialBagReader::SequentialBagReader(const std::string& path) {
  file_.reset(std::fopen(path.c_str(), "rb"));
  if (!file_) throw InvalidInput("'" + path + "': cannot be read: " + std::strerror(errno));
  if (fseeko(file_.get(), 0, SEEK_END) != 0) throw InvalidInput("'" + path + "': cannot be read: " + std::strerror(errno));
  file_size_ = static_cast<std::uint64_t>(ftello(file_.get()));
  char line[kVersionLineLength];
  if (file_size_ < kVersionLineLength || !readAt(0, line, kVersionLineLength) ||
      std::memcmp(line, kVersionLine, kVersionLineLength) != 0) {
    throw InvalidInput("'" + path + "': not a ROS bag of format 2.0 (it does not start with '#ROSBAG V2.0')");
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
  if (r.op != kBagHeader) return fail(r.offset, "the first record is not the bag header (op " + opName(r.op) + ")");
  if (!fixedField(r.fields, "index_pos", index_position_) || !fixedField(r.fields, "chunk_count", chunk_count_)) {
    return fail(r.offset, "bag header without 'index_pos' and 'chunk_count' fields");
  }
  const auto encryptor = r.fields.find("encryptor");
  if (encryptor != r.fields.end() && !encryptor->second.empty()) {
    return fail(r.offset, "encrypted bag (encryptor '" + encryptor->second + "'): its chunks cannot be read without rosbag");
  }
  position_ = r.data_offset + r.data_length;
  return true;
}

/// Reads top-level records up to the next chunk and loads it; false at the end of the file or damage.
bool SequentialBagReader::loadNextChunk() {
  chunk_size_ = chunk_next_ = 0;
  while (position_ < file_size_) {
    Record r;
    if (!readRecord(position_, r)) return false;
    position_ = r.data_offset + r.data_length;
    switch (r.op) {
      case kChunk:
        return loadChunk(r);
      case kConnection:  // the copies at the end of a closed bag
        if (!readTopLevelConnection(r)) return false;
        break;
      case kChunkInfo:
        ++chunk_infos_read_;
        break;
      case kIndexData:
        break;
      default:
        return fail(r.offset, "record op " + opName(r.op) + " where a chunk, index or connection record belongs");
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
  std::uint64_t present = std::min<std::uint64_t>(chunk.data_length, file_size_ - chunk.data_offset);
  if (chunk.data_length == 0 && size == 0) {
    // rosbag writes zero sizes when it opens a chunk and the real ones when it closes it: this one
    // was never closed (the recording stopped). Its records run to the end of the file.
    if (chunk_compressed_) {
      return fail(chunk.offset, "this " + compression->second + " chunk was never finished (a recording cut short): compressed data cannot be read without its size");
    }
    present = file_size_ - chunk.data_offset;
    position_ = file_size_;
    chunk_short_ = "the chunk at byte " + str(chunk.offset) + " was never finished (a recording cut short)";
  } else if (present < chunk.data_length) {
    chunk_short_ = "truncated: the file ends at byte " + str(file_size_) + ", inside the chunk at byte " +
                   str(chunk.offset) + " (" + str(present) + " of its " + str(chunk.data_length) + " bytes present)";
    if (chunk_compressed_) return fail(chunk.offset, chunk_short_ + "; a compressed chunk is read whole: its messages are lost");
  } else if (!chunk_compressed_ && size != chunk.data_length) {
    return fail(chunk.offset, "uncompressed chunk whose size field (" + str(size) + ") differs from its data length (" + str(chunk.data_length) + ")");
  }
  if (chunk_compressed_) return decompress(compression->second, chunk, size);
  chunk_ = readData(chunk.data_offset, present);
  if (!chunk_) return false;
  chunk_size_ = present;
  return true;
}

bool SequentialBagReader::decompress(const std::string& compression, const Record& chunk, std::uint32_t size) {
  if (compression != "lz4" && compression != "bz2") return fail(chunk.offset, "chunk compression '" + compression + "' unknown");
  const std::unique_ptr<std::uint8_t[]> in = readData(chunk.data_offset, chunk.data_length);
  if (!in) return false;
  chunk_.reset(new (std::nothrow) std::uint8_t[std::max<std::uint32_t>(size, 1)]);
  if (!chunk_) return fail(chunk.offset, "cannot allocate the " + str(size) + " bytes its size field asks for (damaged?)");
  unsigned int out = size;
  auto* source = reinterpret_cast<char*>(in.get());
  auto* dest = reinterpret_cast<char*>(chunk_.get());
  const int rc = compression == "lz4" ? roslz4_buffToBuffDecompress(source, chunk.data_length, dest, &out)
                                      : BZ2_bzBuffToBuffDecompress(dest, &out, source, chunk.data_length, 0, 0);
  if (rc != (compression == "lz4" ? ROSLZ4_OK : BZ_OK)) {
    return fail(chunk.offset, "this " + compression + " chunk does not decompress (" + (compression == "lz4" ? "roslz4" : "libbz2") + " code " + std::to_string(rc) + ")");
  }
  if (out != size) return fail(chunk.offset, "this " + compression + " chunk decompresses to " + str(out) + " bytes, its header says " + str(size));
  chunk_size_ = size;
  return true;
}

bool SequentialBagReader::nextInChunk(BagRecordMessage& message) {
  while (chunk_next_ < chunk_size_) {
    const std::size_t at = chunk_next_;
    ChunkRecord r;
    bool cut_off = false;
    const std::string error = parseChunkRecord(chunk_.get() + at, chunk_size_ - at, r, cut_off);
    if (!error.empty()) return failInChunk(at, cut_off && !chunk_short_.empty() ? chunk_short_ + "; this record is cut off" : "damaged record: " + error);
    chunk_next_ = at + r.length;
    if (r.op == kConnection) {
      const std::string bad = parseConnection(r.fields, r.data, r.data_length, connections_);
      if (!bad.empty()) return failInChunk(at, bad);
      continue;
    }
    std::uint32_t id = 0, time[2] = {0, 0};
    if (r.op != kMessageData) return failInChunk(at, "record op " + opName(r.op) + " inside a chunk (only messages and connections belong there)");
    if (!fixedField(r.fields, "conn", id) || !fixedField(r.fields, "time", time)) return failInChunk(at, "message record without 'conn' and 'time' fields");
    const auto connection = connections_.find(id);
    if (connection == connections_.end()) return failInChunk(at, "message on connection " + str(id) + ", which no connection record before it defines");
    message.connection = &connection->second;
    message.time.sec = time[0];  // as rosbag reads it: no normalization
    message.time.nsec = time[1];
    message.data = r.data;
    message.size = r.data_length;
    message.offset = chunk_compressed_ ? chunk_offset_ : chunk_data_offset_ + at;
    return true;
  }
  if (!chunk_short_.empty()) return fail(chunk_data_offset_ + chunk_size_, chunk_short_ + "; it ends after its last whole record");
  return false;
}

bool SequentialBagReader::readTopLevelConnection(const Record& record) {
  const std::unique_ptr<std::uint8_t[]> data = readData(record.data_offset, record.data_length);
  if (!data) return false;
  const std::string error = parseConnection(record.fields, data.get(), record.data_length, connections_);
  return error.empty() || fail(record.offset, error);
}

/// At the end of the file between records: whole if the index was all there, else damage.
bool SequentialBagReader::atEndOfFile() {
  const std::string ends = "the file ends at byte " + str(file_size_);
  if (index_position_ == 0) {
    return fail(file_size_, "the bag was never closed (its header has no index position: a recording cut short); " + ends + ", after its last whole record");
  }
  if (file_size_ < index_position_) {
    return fail(file_size_, "truncated: " + ends + ", before the end of its chunks at byte " + str(index_position_) + " (bag header)");
  }
  if (file_size_ == index_position_ && chunk_count_ > 0) {
    return fail(file_size_, "truncated: " + ends + ", where its index should begin (bag header): the index is missing");
  }
  if (chunk_infos_read_ < chunk_count_) {
    return fail(file_size_, "truncated: " + ends + " inside its index (from byte " + str(index_position_) + "): " +
                                str(chunk_infos_read_) + " of its " + str(chunk_count_) + " chunk info records present");
  }
  return false;
}

/// Reads the header of the top-level record at `offset`; checks that the data of any record but a
/// chunk (which may be cut short: loadChunk) is inside the file.
bool SequentialBagReader::readRecord(std::uint64_t offset, Record& r) {
  r.offset = offset;
  const std::uint64_t left = file_size_ - offset;
  std::uint8_t length[4];
  if (left < 4) return fail(offset, "truncated: the file ends at byte " + str(file_size_) + " inside a record's header length");
  if (!readAt(offset, length, 4)) return fail(offset, std::string("read error: ") + std::strerror(errno));
  const std::uint32_t header_length = u32(length);
  if (left - 4 < header_length + std::uint64_t{4}) {
    return fail(offset, "the file ends at byte " + str(file_size_) + " inside this record (its header claims " + str(header_length) + " bytes): truncated, or a damaged length");
  }
  std::vector<std::uint8_t> header(header_length + std::size_t{4});
  if (!readAt(offset + 4, header.data(), header.size())) return fail(offset, std::string("read error: ") + std::strerror(errno));
  r.fields.clear();
  const std::string error = parseFields(header.data(), header_length, r.fields);
  if (!error.empty()) return fail(offset, "damaged record: " + error);
  if (!fixedField(r.fields, "op", r.op)) return fail(offset, "damaged record: header without a one-byte 'op' field");
  r.data_length = u32(header.data() + header_length);
  r.data_offset = offset + 8 + header_length;
  if (r.op != kChunk && r.data_length > file_size_ - r.data_offset) {
    return fail(offset, "the file ends at byte " + str(file_size_) + " inside this record (its data claims " + str(r.data_length) + " bytes): truncated, or a damaged length");
  }
  return true;
}

std::unique_ptr<std::uint8_t[]> SequentialBagReader::readData(std::uint64_t offset, std::size_t n) {
  std::unique_ptr<std::uint8_t[]> data(new (std::nothrow) std::uint8_t[std::max<std::size_t>(n, 1)]);
  if (!data) {
    fail(offset, "cannot allocate " + str(n) + " bytes to read");
  } else if (!readAt(offset, data.get(), n)) {
    fail(offset, std::string("read error: ") + std::strerror(errno));
    data.reset();
  }
  return data;
}

bool SequentialBagReader::readAt(std::uint64_t offset, void* out, std::size_t n) {
  return fseeko(file_.get(), static_cast<off_t>(offset), SEEK_SET) == 0 && std::fread(out, 1, n, file_.get()) == n;
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
  if (chunk_compressed_) return fail(chunk_offset_, what + " (at byte " + str(at) + " of this chunk's uncompressed data)");
  return fail(chunk_data_offset_ + at, what + " (a record of the chunk at byte " + str(chunk_offset_) + ")");
}

}  // namespace drivetrain_stiffness

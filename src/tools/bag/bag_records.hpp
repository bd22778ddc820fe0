// The records of a ROS bag of format 2.0 (http://wiki.ros.org/Bags/Format/2.0), parsed from bytes
// with every length checked against the bytes that are there before it is used. Shared by
// SequentialBagReader (reads chunks without the index) and checkBagIndex (checks what the index
// promises before rosbag::Bag dereferences it).
//
// Layout: <header_len u32><header><data_len u32><data>, header = repeated <field_len
// u32><name>=<value>, integers little-endian, times as <sec u32><nsec u32>.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <string_view>

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "bag records are little-endian; this reader copies host integers");

namespace drivetrain_stiffness::bag {

/// Record op codes (format 2.0, "Op codes").
enum Op : std::uint8_t {
  kMessageData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07
};

using Fields = std::map<std::string, std::string>;

constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
constexpr std::size_t kVersionLineLength = sizeof kVersionLine - 1;

inline std::uint32_t u32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

std::string opName(std::uint8_t op);

/// Calls visit(name, value) for each <len u32><name>=<value> field filling [p, p + n) exactly
/// (views into the bytes, no copies). Returns what is wrong, or "".
template <typename Visit>
std::string forEachField(const std::uint8_t* p, std::size_t n, Visit&& visit) {
  for (std::size_t i = 0; i < n;) {
    if (n - i < 4) return "header ends inside a field length";
    const std::uint32_t length = u32(p + i);
    i += 4;
    if (length > n - i) {
      return "header field of " + std::to_string(length) + " bytes runs past the header's end (" +
             std::to_string(n - i) + " left)";
    }
    const std::string_view field(reinterpret_cast<const char*>(p + i), length);
    const std::size_t equals = field.find('=');
    if (equals == std::string_view::npos) return "header field without '='";
    visit(field.substr(0, equals), field.substr(equals + 1));
    i += length;
  }
  return "";
}

/// Parses <len u32><name>=<value> fields filling [p, p + n) exactly (a later field of the same name
/// wins, as in ros::Header::parse). Returns what is wrong, or "".
std::string parseFields(const std::uint8_t* p, std::size_t n, Fields& fields);

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
  std::size_t length = 0;  ///< of the whole record
};

/// Parses the record at the start of [p, p + n). Returns what is wrong, or ""; `cut_off` says the
/// record needs bytes beyond n (the end of a truncated chunk, or a damaged length).
std::string parseChunkRecord(const std::uint8_t* p, std::size_t n, ChunkRecord& r, bool& cut_off);

/// Decompresses a chunk ("lz4" or "bz2") of `in_size` bytes whose header claims `size`
/// uncompressed bytes into `out` (allocated here). Returns what is wrong (unknown compression,
/// corrupt data, another size than `size`), or "". Memory follows the data, not the claim: an LZ4
/// chunk may claim at most what LZ4 can expand to (a run length grows by one byte per 255), and a
/// bz2 chunk, which can expand a million-fold on repetitive data, is decompressed in steps into a
/// buffer that grows with its output, so a damaged size field never allocates what it asks for.
std::string decompressChunk(const std::string& compression, const std::uint8_t* in,
                            std::size_t in_size, std::uint32_t size,
                            std::unique_ptr<std::uint8_t[]>& out);

/// A top-level record: its header, and where its data is (read separately, only when needed).
struct TopRecord {
  std::uint64_t offset = 0;
  Fields fields;
  std::uint8_t op = 0;
  std::uint64_t data_offset = 0;
  std::uint32_t data_length = 0;
  std::uint64_t end() const { return data_offset + data_length; }
};

/// A bag file opened for reading at byte offsets.
class BagFile {
 public:
  /// Throws InvalidInput naming the file if it cannot be opened or sized.
  explicit BagFile(const std::string& path);
  std::uint64_t size() const { return size_; }
  bool readAt(std::uint64_t offset, void* out, std::size_t n);
  /// The header of the top-level record at `offset` (a chunk's data may run past the end of the
  /// file: a truncated copy; any other record's must not). Returns what is wrong, or "".
  std::string readRecord(std::uint64_t offset, TopRecord& r);
  /// `n` bytes at `offset`, or null with `error` set.
  std::unique_ptr<std::uint8_t[]> readData(std::uint64_t offset, std::size_t n, std::string& error);

 private:
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_{nullptr, &std::fclose};
  std::uint64_t size_ = 0;
};

/// `n` bytes, uninitialised, or null if they cannot be allocated.
std::unique_ptr<std::uint8_t[]> allocateBytes(std::size_t n);

}  // namespace drivetrain_stiffness::bag

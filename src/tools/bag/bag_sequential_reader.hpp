// A ROS bag (format 2.0) read from the start of the file, chunk after chunk, without its index,
// stopping at the first damage with its byte offset: docs/replay_exit_codes.md "How a damaged bag
// is read".
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <ros/time.h>

#include "bag_records.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {

/// Where and why reading stopped before the end of a bag.
struct BagDamage {
  std::uint64_t offset = 0;  ///< [bytes] of the record or chunk where reading failed
  std::string what;
  /// "'FILE' at byte OFFSET: WHAT"
  std::string describe(const std::string& file) const;
};

/// A connection record: the topic and the publisher's connection header.
struct BagConnection {
  std::string topic;
  std::map<std::string, std::string> header;         ///< type, md5sum, callerid, ...
  std::string field(const std::string& name) const;  ///< empty if absent
  std::uint64_t messages = 0;                        ///< read so far
};

/// One message record, as read.
struct BagRecordMessage {
  const BagConnection* connection = nullptr;
  ros::Time time;                      ///< record time
  const std::uint8_t* data = nullptr;  ///< serialized; valid until the next next()
  std::uint32_t size = 0;
  std::uint64_t offset = 0;  ///< [bytes] of the record, or of its chunk if compressed
};

class SequentialBagReader {
 public:
  /// Throws InvalidInput naming the file if it cannot be read or is not a bag of format 2.0.
  explicit SequentialBagReader(const std::string& path);

  /// The next message record in file order; false at the end or the first damage (damage()).
  bool next(BagRecordMessage& message);
  const std::optional<BagDamage>& damage() const { return damage_; }
  /// [bytes] where the index begins, from the bag header; 0 if not read or never written.
  std::uint64_t indexPosition() const { return index_position_; }
  /// The connections read so far, by id.
  const std::map<std::uint32_t, BagConnection>& connections() const { return connections_; }

 private:
  using Record = bag::TopRecord;
  bool readFileHeader();
  bool loadNextChunk();
  bool loadChunk(const Record& chunk);
  bool decompress(const std::string& compression, const Record& chunk, std::uint32_t size);
  bool nextInChunk(BagRecordMessage& message);
  bool readTopLevelConnection(const Record& record);
  bool atEndOfFile();
  bool readRecord(std::uint64_t offset, Record& record);
  std::unique_ptr<std::uint8_t[]> readData(std::uint64_t offset, std::size_t n);
  bool fail(std::uint64_t offset, const std::string& what);
  bool failInChunk(std::size_t at, const std::string& what);

  bag::BagFile file_;
  std::uint64_t position_ = 0;  ///< next top-level record
  std::uint64_t index_position_ = 0;
  std::uint32_t chunk_count_ = 0, chunk_infos_read_ = 0;
  std::map<std::uint32_t, BagConnection> connections_;
  // The chunk being read, uncompressed; not value-initialized (a damaged size is never touched).
  std::unique_ptr<std::uint8_t[]> chunk_;
  std::size_t chunk_size_ = 0, chunk_next_ = 0;
  std::uint64_t chunk_offset_ = 0;       ///< its record in the file
  std::uint64_t chunk_data_offset_ = 0;  ///< of its data
  bool chunk_compressed_ = false;
  std::string chunk_short_;  ///< why its data ends early; empty if whole
  std::optional<BagDamage> damage_;
};

}  // namespace drivetrain_stiffness

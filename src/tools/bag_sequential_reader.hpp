// SequentialBagReader: reads the message records of a ROS bag (format 2.0) from the start of the
// file, chunk after chunk, without the index at its end, and stops at the first damage, saying
// where (byte offset) and what. drivetrain_replay uses it for a bag that rosbag::Bag cannot open
// (a recording cut short has no index) and to locate the damage rosbag meets in the middle of a
// bag (rosbag's errors name no offset).
//
// Why a reader of our own (checked on Debian 12's rosbag 1.15.15):
// - rosbag::Bag::open reads the index at the end of the file before anything else: an unclosed
//   recording throws BagUnindexedException, a truncated copy of a closed bag "Error reading from
//   file: wanted 4 bytes, read 0 bytes" (its header points past the end). rosbag::Bag has no public
//   way to read chunks without the index (bag.h: readChunkHeader, decompressChunk etc. are
//   private), and bagmode::Append reads the same index first (openAppend calls
//   startReadingVersion200).
// - `rosbag reindex` (python3-rosbag, _BagReader200.reindex) on a temporary copy would mean a
//   Python subprocess and a copy of the whole bag, and it loses what we want to keep: on the
//   first chunk it cannot read (truncated, unterminated, undecompressable) it drops that whole
//   chunk and stops ("except Exception: break") without saying where or why, so the messages
//   before the damage inside that chunk are lost and the error has no offset.
// - The format (http://wiki.ros.org/Bags/Format/2.0) is small, the project writes it already
//   (bag_writer.cpp), and chunks decompress with the libraries rosbag uses (roslz4, libbz2).
// Every length read from the file is checked against the bytes that are there before it is used.
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
  std::uint64_t offset =
      0;  ///< byte offset in the file of the record or chunk where reading failed
  std::string what;
  /// "'FILE' at byte OFFSET: WHAT"
  std::string describe(const std::string& file) const;
};

/// A connection record: the topic and the publisher's connection header.
struct BagConnection {
  std::string topic;
  std::map<std::string, std::string> header;  ///< type, md5sum, message_definition, callerid, ...
  std::string field(const std::string& name) const;  ///< empty if absent
  std::uint64_t messages = 0;                        ///< message records read on it so far
};

/// One message record, as read.
struct BagRecordMessage {
  const BagConnection* connection = nullptr;
  ros::Time time;                      ///< record time
  const std::uint8_t* data = nullptr;  ///< serialized message; valid until the next call to next()
  std::uint32_t size = 0;
  /// Byte offset of the record in the file in an uncompressed chunk; of its chunk in a compressed
  /// one.
  std::uint64_t offset = 0;
};

class SequentialBagReader {
 public:
  /// Opens `path` and reads its version line. Throws InvalidInput naming the file if it cannot be
  /// read or is not a bag of format 2.0.
  explicit SequentialBagReader(const std::string& path);

  /// The next message record in file order. False at the end of the bag or at the first damage
  /// (damage() says which); a bag whose index is missing ends in damage.
  bool next(BagRecordMessage& message);
  const std::optional<BagDamage>& damage() const { return damage_; }
  /// Where the chunks end and the index begins, from the bag header; 0 if not read or never
  /// written.
  std::uint64_t indexPosition() const { return index_position_; }
  /// The connections read so far, by id, with the messages read on each.
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
  // The chunk being read: its uncompressed records, not value-initialized (a damaged size field
  // may ask for gigabytes: reserved, never touched).
  std::unique_ptr<std::uint8_t[]> chunk_;
  std::size_t chunk_size_ = 0, chunk_next_ = 0;
  std::uint64_t chunk_offset_ = 0;  ///< its record in the file
  std::uint64_t chunk_data_offset_ =
      0;  ///< of its data (uncompressed chunks: record offsets in the file)
  bool chunk_compressed_ = false;
  std::string chunk_short_;  ///< why its data ends early (truncated, unfinished); empty if whole
  std::optional<BagDamage> damage_;
};

}  // namespace drivetrain_stiffness

#include "bag_index_check.hpp"  // NOLINT(build/include_subdir)

#include <map>
#include <stdexcept>

#include "bag_records.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

using namespace bag;  // NOLINT(build/namespaces): the record vocabulary

std::string str(std::uint64_t n) { return std::to_string(n); }

struct IndexEntry {
  std::uint32_t sec = 0, nsec = 0, offset = 0;
  /// librosbag drops an entry before ros::TIME_MIN (time 0) when it reads the index
  /// (readConnectionIndexRecord200): the view never visits it.
  bool visited() const { return sec != 0 || nsec != 0; }
};

/// A chunk as the index describes it: its header and the index data records after it.
struct IndexedChunk {
  TopRecord record;
  std::string compression;
  std::uint32_t size = 0;                                    ///< uncompressed
  std::map<std::uint32_t, std::vector<IndexEntry>> entries;  ///< per connection
};

/// The record time a view orders by: ros::Time(sec, nsec) as rosbag builds it (nsec normalised).
std::optional<ros::Time> viewTime(const IndexEntry& e) {
  try {
    return ros::Time(e.sec, e.nsec);
  } catch (const std::runtime_error&) {  // seconds overflow after normalising
    return std::nullopt;
  }
}

class Checker {
 public:
  Checker(const std::string& path, const ReadRules& rules)
      : path_(path), file_(path), rules_(rules) {}

  BagIndexCheck run() {
    if (readBagHeader() && readChunks() && readIndex() && crossCheck()) {
      result_.usable = true;
      for (const IndexedChunk& chunk : chunks_) checkChunk(chunk);
    }
    for (const auto& [id, connection] : connections_) {
      std::uint64_t messages = 0;
      for (const IndexedChunk& chunk : chunks_) {
        const auto it = chunk.entries.find(id);
        if (it == chunk.entries.end()) continue;
        for (const IndexEntry& e : it->second) messages += e.visited() ? 1 : 0;
      }
      result_.topics.push_back(
          {connection.topic, connection.field("type"), connection.field("md5sum"), messages});
    }
    return std::move(result_);
  }

 private:
  bool indexDamage(std::uint64_t offset, const std::string& what) {
    if (!result_.index_damage)
      result_.index_damage = BagDamage{offset, "the index is damaged: " + what};
    return false;
  }
  bool read(std::uint64_t offset, TopRecord& r) {
    const std::string error = file_.readRecord(offset, r);
    return error.empty() || indexDamage(offset, error);
  }

  /// Rosbag's readFileHeaderRecord: index_pos, conn_count, chunk_count, no encryptor.
  bool readBagHeader() {
    char line[kVersionLineLength];
    if (file_.size() < kVersionLineLength || !file_.readAt(0, line, kVersionLineLength) ||
        std::memcmp(line, kVersionLine, kVersionLineLength) != 0) {
      throw InvalidInput("'" + path_ +
                         "': not a ROS bag of format 2.0 (it does not start with '#ROSBAG V2.0')");
    }
    TopRecord r;
    if (!read(kVersionLineLength, r)) return false;
    if (r.op != kBagHeader) return indexDamage(r.offset, "the first record is not the bag header");
    if (!fixedField(r.fields, "index_pos", index_pos_) ||
        !fixedField(r.fields, "conn_count", connection_count_) ||
        !fixedField(r.fields, "chunk_count", chunk_count_)) {
      return indexDamage(r.offset,
                         "bag header without 'index_pos', 'conn_count' and 'chunk_count' fields");
    }
    const auto encryptor = r.fields.find("encryptor");
    if (encryptor != r.fields.end() && !encryptor->second.empty()) {
      return indexDamage(r.offset, "an encrypted bag (encryptor '" + encryptor->second + "')");
    }
    if (index_pos_ == 0)
      return indexDamage(r.offset, "the bag was never closed (no index position)");
    if (index_pos_ < r.end() || index_pos_ > file_.size()) {
      return indexDamage(r.offset, "the index position " + str(index_pos_) +
                                       " lies outside the file's " + str(file_.size()) + " bytes");
    }
    chunks_start_ = r.end();
    return true;
  }

  /// The chunk headers and the index data records after each, from the bag header to index_pos.
  bool readChunks() {
    for (std::uint64_t at = chunks_start_; at < index_pos_;) {
      TopRecord r;
      if (!read(at, r)) return false;
      if (r.end() > index_pos_)
        return indexDamage(at, "a record runs past the index position " + str(index_pos_));
      at = r.end();
      if (r.op == kChunk) {
        IndexedChunk chunk;
        chunk.record = r;
        const auto compression = r.fields.find("compression");
        if (compression == r.fields.end() || !fixedField(r.fields, "size", chunk.size)) {
          return indexDamage(r.offset, "chunk header without 'compression' and 'size' fields");
        }
        chunk.compression = compression->second;
        if (chunk.compression == "none" && chunk.size != r.data_length) {
          return indexDamage(r.offset, "the uncompressed chunk's size field (" + str(chunk.size) +
                                           ") differs from its data length (" + str(r.data_length) +
                                           ")");
        }
        chunks_.push_back(std::move(chunk));
      } else if (r.op == kIndexData) {
        if (chunks_.empty() || !readIndexData(r))
          return indexDamage(r.offset, "an index data record out of place");
      } else if (r.op != kConnection) {
        return indexDamage(r.offset, "record op " + opName(r.op) + " among the chunks");
      }
    }
    return true;
  }

  /// Rosbag's readConnectionIndexRecord200: ver 1, conn, count, then count (time, offset) entries.
  bool readIndexData(const TopRecord& r) {
    std::uint32_t version = 0, connection = 0, count = 0;
    if (!fixedField(r.fields, "ver", version) || version != 1 ||
        !fixedField(r.fields, "conn", connection) || !fixedField(r.fields, "count", count) ||
        std::uint64_t{count} * 12 != r.data_length) {
      return false;
    }
    std::string error;
    const std::unique_ptr<std::uint8_t[]> data =
        file_.readData(r.data_offset, r.data_length, error);
    if (!data) return indexDamage(r.offset, error);
    std::vector<IndexEntry>& entries = chunks_.back().entries[connection];
    if (!entries.empty()) return false;  // two index records of one connection after one chunk
    entries.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
      const std::uint8_t* e = data.get() + 12 * std::size_t{i};
      entries[i] = {u32(e), u32(e + 4), u32(e + 8)};
    }
    return true;
  }

  /// At index_pos: conn_count connection records, then chunk_count chunk info records, to the end.
  bool readIndex() {
    std::uint64_t at = index_pos_;
    for (std::uint32_t i = 0; i < connection_count_; ++i) {
      TopRecord r;
      if (!read(at, r)) return false;
      std::uint32_t id = 0;
      const auto topic = r.fields.find("topic");
      if (r.op != kConnection || !fixedField(r.fields, "conn", id) || topic == r.fields.end()) {
        return indexDamage(
            at, "connection record " + str(i + 1) + " of " + str(connection_count_) + " expected");
      }
      std::string error;
      const std::unique_ptr<std::uint8_t[]> data =
          file_.readData(r.data_offset, r.data_length, error);
      if (!data) return indexDamage(at, error);
      BagConnection connection;
      connection.topic = topic->second;
      error = parseFields(data.get(), r.data_length, connection.header);
      if (!error.empty()) return indexDamage(at, "connection header: " + error);
      // A repeated id: the first record wins, as in librosbag's readConnectionRecord (the view
      // reads the topic it names).
      connections_.try_emplace(id, std::move(connection));
      at = r.end();
    }
    for (std::uint32_t i = 0; i < chunk_count_; ++i) {
      TopRecord r;
      if (!read(at, r)) return false;
      if (r.op != kChunkInfo || !readChunkInfo(r)) {
        return indexDamage(
            at, "chunk info record " + str(i + 1) + " of " + str(chunk_count_) + " expected");
      }
      at = r.end();
    }
    if (at != file_.size())
      return indexDamage(at, str(file_.size() - at) + " bytes after the last index record");
    return true;
  }

  /// Rosbag's readChunkInfoRecord: ver 1, chunk_pos, start and end time, count, (conn, count)
  /// pairs.
  bool readChunkInfo(const TopRecord& r) {
    std::uint32_t version = 0, count = 0;
    std::uint64_t position = 0;
    std::uint64_t time = 0;
    if (!fixedField(r.fields, "ver", version) || version != 1 ||
        !fixedField(r.fields, "chunk_pos", position) || !fixedField(r.fields, "start_time", time) ||
        !fixedField(r.fields, "end_time", time) || !fixedField(r.fields, "count", count) ||
        std::uint64_t{count} * 8 != r.data_length) {
      return false;
    }
    std::string error;
    const std::unique_ptr<std::uint8_t[]> data =
        file_.readData(r.data_offset, r.data_length, error);
    if (!data) return false;
    std::map<std::uint32_t, std::uint32_t> counts;
    for (std::uint32_t i = 0; i < count; ++i)
      counts[u32(data.get() + 8 * std::size_t{i})] = u32(data.get() + 8 * std::size_t{i} + 4);
    chunk_infos_.push_back({position, std::move(counts)});
    return true;
  }

  /// Every chunk info names a chunk once, and its counts are the chunk's index data records: what
  /// rosbag reads after each chunk. Every entry's connection is defined, its time representable.
  bool crossCheck() {
    if (chunk_infos_.size() != chunks_.size()) {
      return indexDamage(index_pos_, str(chunk_infos_.size()) + " chunk info records for " +
                                         str(chunks_.size()) + " chunks");
    }
    for (std::size_t i = 0; i < chunks_.size(); ++i) {
      const IndexedChunk& chunk = chunks_[i];
      const auto& [position, counts] = chunk_infos_[i];
      if (position != chunk.record.offset || counts.size() != chunk.entries.size()) {
        return indexDamage(chunk.record.offset, "its chunk info record does not describe it");
      }
      for (const auto& [id, entries] : chunk.entries) {
        const auto count = counts.find(id);
        if (count == counts.end() || count->second != entries.size() || !connections_.count(id)) {
          return indexDamage(chunk.record.offset, "its index of connection " + str(id) +
                                                      " disagrees with the chunk info");
        }
        for (const IndexEntry& e : entries) {
          if (!viewTime(e))
            return indexDamage(chunk.record.offset, "an index entry's time is out of range");
        }
      }
    }
    return true;
  }

  const ReadRule& ruleOf(std::uint32_t id) {
    const auto it = rules_cache_.find(id);
    if (it != rules_cache_.end()) return it->second;
    return rules_cache_[id] = rules_(connections_.at(id));
  }

  /// The records and messages of `chunk` that the view will read.
  void checkChunk(const IndexedChunk& chunk) {
    bool any = false;
    for (const auto& [id, entries] : chunk.entries)
      any = any || (ruleOf(id).read && !entries.empty());
    if (!any) return;
    const TopRecord& r = chunk.record;
    const bool compressed = chunk.compression != "none";
    std::string error;
    std::unique_ptr<std::uint8_t[]> data = file_.readData(r.data_offset, r.data_length, error);
    if (data && compressed) {
      std::unique_ptr<std::uint8_t[]> out;
      error = decompressChunk(chunk.compression, data.get(), r.data_length, chunk.size, out);
      data = error.empty() ? std::move(out) : nullptr;
    }
    for (const auto& [id, entries] : chunk.entries) {
      const ReadRule& rule = ruleOf(id);
      if (!rule.read) continue;
      for (const IndexEntry& e : entries) {
        if (!e.visited()) continue;
        // A compressed chunk's damage is placed at its record (read whole), an uncompressed one's
        // at the message record.
        const std::uint64_t where =
            compressed || e.offset >= chunk.size ? r.offset : r.data_offset + e.offset;
        const std::string what = data ? checkEntry(id, e, data.get(), chunk.size, rule) : error;
        if (!what.empty()) badEntry(e, where, id, what);
      }
    }
  }

  /// The record at the entry's offset: a message record of that connection and time, inside the
  /// chunk, whose bytes hold the rule's layout. Returns what is wrong, or "".
  std::string checkEntry(std::uint32_t id, const IndexEntry& e, const std::uint8_t* chunk,
                         std::size_t size, const ReadRule& rule) const {
    if (e.offset >= size)
      return "its index offset " + str(e.offset) + " lies past the chunk's " + str(size) + " bytes";
    const std::uint8_t* p = chunk + e.offset;
    const std::size_t n = size - e.offset;
    if (n < 8) return "record cut off at the chunk's end";
    const std::uint32_t header_length = u32(p);
    if (n - 8 < header_length)
      return "record header of " + str(header_length) + " bytes runs past the chunk's end";
    const std::uint32_t data_length = u32(p + 4 + header_length);
    if (n - 8 - header_length < data_length)
      return "record data of " + str(data_length) + " bytes runs past the chunk's end";
    std::uint8_t op = 0;
    std::uint32_t connection = 0;
    std::uint64_t time = ~std::uint64_t{0};
    int found = 0;
    const std::string bad =
        forEachField(p + 4, header_length, [&](std::string_view name, std::string_view value) {
          if (name == "op" && value.size() == 1) {
            op = static_cast<std::uint8_t>(value[0]);
            found |= 1;
          } else if (name == "conn" && value.size() == 4) {
            std::memcpy(&connection, value.data(), 4);
            found |= 2;
          } else if (name == "time" && value.size() == 8) {
            std::memcpy(&time, value.data(), 8);
            found |= 4;
          }
        });
    if (!bad.empty()) return "damaged record: " + bad;
    if (found != 7 || op != kMessageData) return "not a message record (op, conn and time fields)";
    const std::uint64_t entry_time = std::uint64_t{e.nsec} << 32 | e.sec;
    if (connection != id || time != entry_time)
      return "the record's connection and time are not the index entry's";
    if (!rule.layout) return "";
    const std::string layout =
        checkSerializedMessage(*rule.layout, p + 8 + header_length, data_length);
    return layout.empty() ? "" : "the message does not deserialize: " + layout;
  }

  void badEntry(const IndexEntry& e, std::uint64_t where, std::uint32_t id,
                const std::string& what) {
    const ros::Time t = *viewTime(e);
    if (result_.stop &&
        (t > *result_.stop || (t == *result_.stop && where >= result_.damage->offset)))
      return;
    result_.stop = t;
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%u.%09u", t.sec, t.nsec);
    result_.damage = BagDamage{
        where, "the " + connections_.at(id).topic + " message at record time " + stamp +
                   " is damaged: " + what + "; the messages before it are read through the index"};
  }

  std::string path_;
  BagFile file_;
  const ReadRules& rules_;
  BagIndexCheck result_;
  std::uint64_t index_pos_ = 0, chunks_start_ = 0;
  std::uint32_t connection_count_ = 0, chunk_count_ = 0;
  std::vector<IndexedChunk> chunks_;
  std::vector<std::pair<std::uint64_t, std::map<std::uint32_t, std::uint32_t>>> chunk_infos_;
  std::map<std::uint32_t, BagConnection> connections_;
  std::map<std::uint32_t, ReadRule> rules_cache_;
};

}  // namespace

BagIndexCheck checkBagIndex(const std::string& path, const ReadRules& rules) {
  return Checker(path, rules).run();
}

}  // namespace drivetrain_stiffness

// The vibration input stage: accelerometer blocks (msg/VibrationBlock.msg) through the block rules,
// each known channel mapped to a shaft's transverse coordinate, kept as one continuous record
// (docs/vibration.md "Input"). ROS-free; allocates only when a record starts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/vibration_channels.hpp"

namespace drivetrain_stiffness {

/// A block as the pipeline reads it: `channel_count` names and `size` samples, interleaved by
/// sample (data[i * channel_count + c]) [m/s^2], sampled at `sample_rate` [Hz].
struct VibrationBlockView {
  double sample_rate = 0.0;
  const std::string* channels = nullptr;
  std::size_t channel_count = 0;
  const float* data = nullptr;
  std::size_t size = 0;
};

/// The block rules and the continuous record of the mapped channels.
class VibrationInput {
 public:
  static constexpr std::size_t kMaxChannels = 64;
  static constexpr double kMaxSampleRate = 1e7;       ///< [Hz]
  static constexpr double kMaxAcceleration = 1e6;     ///< [m/s^2], past any accelerometer's range
  static constexpr std::size_t kMaxUnknownNames = 8;  ///< distinct unknown names kept for reports
  static constexpr double kMaxRecordBytes = 256.0 * 1048576.0;  ///< the record's ring at most
  /// Rates within this relative difference are one rate (a converter that reports its measured
  /// rate) [-].
  static constexpr double kRateTolerance = 1e-6;

  /// `record_seconds` [s] of the newest samples are kept (InvalidInput unless in (0, 600]).
  VibrationInput(std::vector<VibrationChannel> channels, double record_seconds);

  /// The value rules: rate in (0, kMaxSampleRate], 1 to kMaxChannels distinct non-empty names, at
  /// least one known, a whole number of samples, every value finite and within kMaxAcceleration.
  /// Throws InvalidInput naming the field and value.
  void validate(const VibrationBlockView& block) const;
  /// The continuity rules at `stamp` (the first sample's time) and `seq` (header.seq; 0 throughout:
  /// unnumbered), then the block appended. Throws InvalidInput, nothing changed, when the block
  /// overlaps the record.
  void append(Stamp stamp, const VibrationBlockView& block, std::uint32_t seq = 0);
  /// A block was refused: the next one starts a new record (its samples are missing).
  void interrupt();
  const VibrationCounters& counters() const { return counters_; }
  /// Forgets the record (a pipeline reset); the counters stay.
  void reset();

  /// Unknown channel names seen, by first appearance (at most kMaxUnknownNames).
  const std::vector<std::string>& unknownNames() const { return unknown_names_; }
  const std::vector<VibrationChannel>& channelMap() const { return map_; }

  // --- The record: frames [0, frames()) of columns() mapped channels, oldest first ---
  bool recording() const { return !columns_.empty(); }
  double sampleRate() const { return rate_; }
  std::size_t columns() const { return columns_.size(); }
  /// The mapped channel of column `c` (its name, shaft and sign).
  const VibrationChannel& column(std::size_t c) const { return map_[columns_[c].map_index]; }
  std::size_t frames() const { return frames_; }
  /// Frames the record holds when full (~vibration_record at its rate).
  std::size_t capacity() const { return capacity_; }
  /// Frames appended since the record started (a new record starts at its first block's frames).
  std::uint64_t appended() const { return appended_; }
  /// Acceleration of column c at frame i, sign applied [m/s^2].
  float value(std::size_t c, std::size_t i) const;
  /// Time of frame i [s] relative to `origin()`: the record's first sample.
  double frameTime(std::size_t i) const;
  Stamp origin() const;

 private:
  struct Column {
    std::size_t block_index = 0;  ///< position among the block's channels
    std::size_t map_index = 0;    ///< entry of map_
  };
  enum class Continuity { kContinues, kGap, kOverlap };
  /// Whether a block of `frames` at `stamp`, numbered `seq`, continues the record.
  Continuity continuity(Stamp stamp, std::uint32_t seq, std::size_t frames) const;
  bool sameRate(double rate) const;
  std::size_t recordFrames(double rate) const;  ///< the ring's frames at `rate` [Hz]
  /// The mapped channel named `name`, or -1.
  int find(std::string_view name) const;
  bool sameLayout(const VibrationBlockView& block) const;
  void start(Stamp stamp, const VibrationBlockView& block);
  void noteUnknown(const VibrationBlockView& block);

  std::vector<VibrationChannel> map_;
  double record_seconds_;
  VibrationCounters counters_;
  std::vector<std::string> unknown_names_;
  // The record.
  double rate_ = 0.0;
  std::vector<std::string> layout_;  ///< the block channel names the record was started with
  std::vector<Column> columns_;
  /// capacity_ frames x columns, frame-major; only frames [0, frames_) are read, so it is left
  /// uninitialised: its pages are touched block by block, not all at a record's start.
  std::unique_ptr<float[]> ring_;
  std::size_t ring_size_ = 0;  ///< ring_'s floats
  std::size_t capacity_ = 0, head_ = 0, frames_ = 0;
  Stamp start_;                  ///< stamp of the record's first sample ever appended
  std::uint64_t appended_ = 0;   ///< frames appended since start_
  Stamp last_stamp_;             ///< the last block's first sample
  std::size_t last_frames_ = 0;  ///< and its frames
  std::uint32_t last_seq_ = 0;   ///< and its header.seq
  bool interrupted_ = false;     ///< a block refused since the last one taken
};

}  // namespace drivetrain_stiffness

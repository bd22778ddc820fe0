#include "drivetrain_stiffness/pipeline/vibration_input.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

namespace {
std::string quoted(std::string_view name) { return "'" + printableText(name) + "'"; }

std::string namesOf(const VibrationBlockView& block) {
  std::string names;
  for (std::size_t c = 0; c < block.channel_count; ++c) {
    names += (c ? ", " : "") + quoted(block.channels[c]);
  }
  return names;
}
}  // namespace

VibrationInput::VibrationInput(std::vector<VibrationChannel> channels, double record_seconds)
    : map_(std::move(channels)), record_seconds_(record_seconds) {
  if (!(record_seconds > 0.0 && record_seconds <= 600.0)) {
    throwInvalid("vibration_record", record_seconds, "must be in (0, 600] s");
  }
}

int VibrationInput::find(std::string_view name) const {
  for (std::size_t i = 0; i < map_.size(); ++i) {
    if (map_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void VibrationInput::validate(const VibrationBlockView& b) const {
  if (!(b.sample_rate > 0.0 && b.sample_rate <= kMaxSampleRate)) {
    throwInvalid("vibration: sample_rate", b.sample_rate,
                 "must be in (0, " + formatValue(kMaxSampleRate) + "] Hz");
  }
  if (b.channel_count == 0 || b.channel_count > kMaxChannels) {
    throwInvalid("vibration: channels.size()", static_cast<double>(b.channel_count),
                 "must be 1 to " + std::to_string(kMaxChannels));
  }
  bool known = false;
  for (std::size_t c = 0; c < b.channel_count; ++c) {
    if (b.channels[c].empty())
      throw InvalidInput("vibration: channels[" + std::to_string(c) + "] is empty");
    for (std::size_t d = 0; d < c; ++d) {
      if (b.channels[d] == b.channels[c]) {
        throw InvalidInput("vibration: channels[" + std::to_string(c) + "] = " +
                           quoted(b.channels[c]) + " repeats channels[" + std::to_string(d) + "]");
      }
    }
    known = known || find(b.channels[c]) >= 0;
  }
  if (!known) {
    std::string supports;
    for (const VibrationChannel& m : map_)
      supports += (supports.empty() ? "" : ", ") + quoted(m.name);
    throw InvalidInput("vibration: channels = [" + namesOf(b) +
                       "]: none names a bearing support or a ~vibration_channels entry (" +
                       supports + ")");
  }
  std::size_t width = 0;
  for (std::size_t c = 0; c < b.channel_count; ++c) width += find(b.channels[c]) >= 0 ? 1 : 0;
  const double bytes = static_cast<double>(recordFrames(b.sample_rate)) * width * sizeof(float);
  if (bytes > kMaxRecordBytes) {
    throwInvalid("vibration: sample_rate", b.sample_rate,
                 "with ~vibration_record = " + formatValue(record_seconds_) + " s and " +
                     std::to_string(width) + " mapped channels the record needs " +
                     formatValue(bytes / 1048576.0) + " MiB, more than " +
                     formatValue(kMaxRecordBytes / 1048576.0) + " MiB");
  }
  if (b.size == 0 || b.size % b.channel_count != 0) {
    throw InvalidInput("vibration: data.size() = " + std::to_string(b.size) + " for " +
                       std::to_string(b.channel_count) +
                       " channels: must be a positive multiple of the channel count");
  }
  for (std::size_t i = 0; i < b.size; ++i) {
    const double a = b.data[i];
    if (!(std::abs(a) <= kMaxAcceleration)) {
      const std::size_t c = i % b.channel_count;
      throwInvalid("vibration: data[" + std::to_string(i) + "] (channel " + quoted(b.channels[c]) +
                       ", sample " + std::to_string(i / b.channel_count) + ")",
                   a, "must be finite and within +-" + formatValue(kMaxAcceleration) + " m/s^2");
    }
  }
}

bool VibrationInput::sameLayout(const VibrationBlockView& b) const {
  if (b.channel_count != layout_.size()) return false;
  for (std::size_t c = 0; c < b.channel_count; ++c) {
    if (b.channels[c] != layout_[c]) return false;
  }
  return true;
}

bool VibrationInput::sameRate(double rate) const {
  return std::abs(rate - rate_) <= kRateTolerance * rate_;
}

VibrationInput::Continuity VibrationInput::continuity(Stamp stamp, std::uint32_t seq,
                                                      std::size_t frames) const {
  if (interrupted_) return Continuity::kGap;  // a refused block's samples are missing
  const double late = secondsBetween(stamp, last_stamp_) - last_frames_ / rate_;
  const double block = std::min<double>(last_frames_, frames) / rate_;
  if (seq != 0 || last_seq_ != 0) {
    // Numbered blocks: the numbers say what is next; the stamps only catch a paused acquisition
    // (more than a whole block off) under continuing numbers.
    if (seq == last_seq_) return Continuity::kOverlap;  // the same block again
    if (seq != last_seq_ + 1 || late >= block) return Continuity::kGap;
    return late <= -block ? Continuity::kOverlap : Continuity::kContinues;
  }
  // Unnumbered: the stamps against the previous block's end, within half the shorter block.
  if (late <= -0.5 * block) return Continuity::kOverlap;
  if (late >= 0.5 * block) return Continuity::kGap;
  return Continuity::kContinues;
}

void VibrationInput::append(Stamp stamp, const VibrationBlockView& b, std::uint32_t seq) {
  const std::size_t frames = b.size / b.channel_count;
  if (!recording()) {
    start(stamp, b);
  } else if (!sameRate(b.sample_rate)) {
    ++counters_.rate_changes;
    start(stamp, b);
  } else if (!sameLayout(b)) {
    ++counters_.channel_changes;
    start(stamp, b);
  } else {
    switch (continuity(stamp, seq, frames)) {
      case Continuity::kContinues: break;
      case Continuity::kGap:
        ++counters_.gaps;
        start(stamp, b);
        break;
      case Continuity::kOverlap: {
        ++counters_.overlaps;
        const double early = last_frames_ / rate_ - secondsBetween(stamp, last_stamp_);
        throw InvalidInput(
            "vibration: header.seq = " + std::to_string(seq) +
            ": overlaps the previous block (header.seq = " + std::to_string(last_seq_) +
            "), starting " + formatValue(early) + " s before its end");
      }
    }
  }
  const std::size_t width = columns_.size();
  for (std::size_t i = 0; i < frames; ++i) {
    float* frame = &ring_[head_ * width];
    for (std::size_t c = 0; c < width; ++c) {
      const VibrationChannel& m = map_[columns_[c].map_index];
      frame[c] = static_cast<float>(m.sign) * b.data[i * b.channel_count + columns_[c].block_index];
    }
    head_ = (head_ + 1) % capacity_;
    frames_ = std::min(frames_ + 1, capacity_);
  }
  appended_ += frames;
  counters_.samples += frames;
  counters_.unknown_channels += b.channel_count - width;
  if (b.channel_count > width) noteUnknown(b);
  last_stamp_ = stamp;
  last_frames_ = frames;
  last_seq_ = seq;
  interrupted_ = false;
}

std::size_t VibrationInput::recordFrames(double rate) const {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(record_seconds_ * rate)));
}

void VibrationInput::start(Stamp stamp, const VibrationBlockView& b) {
  // The ring first: if it cannot be had, the record before stays as it was. A ring of the same
  // size is kept (a gap or a layout change at the same rate allocates nothing).
  std::size_t width = 0;
  for (std::size_t c = 0; c < b.channel_count; ++c) width += find(b.channels[c]) >= 0 ? 1 : 0;
  const std::size_t size = recordFrames(b.sample_rate) * width;
  if (size != ring_size_) {
    ring_ = std::unique_ptr<float[]>(new float[size]);  // default-initialised: not zeroed
    ring_size_ = size;
  }
  rate_ = b.sample_rate;
  layout_.assign(b.channels, b.channels + b.channel_count);
  columns_.clear();
  for (std::size_t c = 0; c < b.channel_count; ++c) {
    const int m = find(b.channels[c]);
    if (m >= 0) columns_.push_back({c, static_cast<std::size_t>(m)});
  }
  capacity_ = recordFrames(rate_);
  head_ = frames_ = 0;
  start_ = stamp;
  appended_ = 0;
}

void VibrationInput::noteUnknown(const VibrationBlockView& b) {
  for (std::size_t c = 0; c < b.channel_count && unknown_names_.size() < kMaxUnknownNames; ++c) {
    const std::string& name = b.channels[c];
    if (find(name) < 0 &&
        std::find(unknown_names_.begin(), unknown_names_.end(), name) == unknown_names_.end()) {
      unknown_names_.push_back(printableText(name));
    }
  }
}

void VibrationInput::interrupt() { interrupted_ = true; }

void VibrationInput::reset() {
  interrupted_ = false;
  last_seq_ = 0;
  columns_.clear();
  layout_.clear();
  frames_ = head_ = capacity_ = 0;
  appended_ = 0;
  rate_ = 0.0;
}

float VibrationInput::value(std::size_t c, std::size_t i) const {
  const std::size_t oldest = (head_ + capacity_ - frames_) % capacity_;
  return ring_[((oldest + i) % capacity_) * columns_.size() + c];
}

double VibrationInput::frameTime(std::size_t i) const { return static_cast<double>(i) / rate_; }

Stamp VibrationInput::origin() const {
  const double offset = static_cast<double>(appended_ - frames_) / rate_;
  return Stamp{start_.ns + static_cast<std::int64_t>(std::llround(offset * 1e9))};
}

}  // namespace drivetrain_stiffness

// What a replay used of a bag and what it did not, and why: per input topic the messages read,
// accepted and refused by reason (with the first refusal's stamp and, for a frame or joint-name
// mismatch, what was found against what was expected), the wrong types found, and for a named
// topic the bag does not hold, the bag's topics with their types. drivetrain_replay prints it on
// stderr at the end of every run and writes it to summary.json ("inputs") and report.md.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bag/bag_index_check.hpp"  // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace drivetrain_stiffness {

/// One input the replay reads from the bag: its topic and the type it wants.
struct ReplayInputTopic {
  InputStream stream;
  std::string option;         ///< the command-line option that names the topic
  std::string topic;          ///< as named (with or without a leading '/')
  std::string expected_type;  ///< e.g. "geometry_msgs/WrenchStamped"
  std::uint64_t read = 0;     ///< messages on the topic, of any type
  std::map<std::string, std::uint64_t>
      wrong_types;  ///< recorded type -> messages (not the expected type)
  std::uint64_t wrongType() const;
};

class ReplaySummary {
 public:
  /// Each stream's topic, indexed by InputStream.
  explicit ReplaySummary(const std::array<std::string, kInputStreams>& topics);
  /// Throws InvalidInput naming both options when one topic is named for two inputs.
  void requireDistinctTopics() const;
  ReplayInputTopic& input(InputStream stream) { return inputs_[static_cast<std::size_t>(stream)]; }
  /// Counts one message read on `stream`'s topic; `type` is its recorded type when it is not the
  /// one wanted (wrong_type), empty otherwise.
  void read(InputStream stream, const std::string& type = {});
  std::uint64_t wrongType() const;

  /// Accepted inputs on every topic (the pipeline's counters).
  static std::uint64_t accepted(const PipelineCounters& c);
  /// The bag was read up to damage: a named topic the bag holds but nothing was read of is said
  /// to be cut off, not absent.
  void markDamaged() { damaged_ = true; }
  nlohmann::json json(const RigPipeline& pipeline, const std::vector<BagTopic>& bag_topics) const;
  /// The plain-text summary for stderr, one screen.
  std::string text(const RigPipeline& pipeline, const std::vector<BagTopic>& bag_topics) const;
  /// The same as Markdown, for report.md.
  std::string markdown(const RigPipeline& pipeline, const std::vector<BagTopic>& bag_topics) const;
  /// The wrong-type messages, one line per topic and type found, for stderr ("" if none).
  std::string wrongTypeText() const;

 private:
  std::array<ReplayInputTopic, kInputStreams> inputs_;
  bool damaged_ = false;
};

}  // namespace drivetrain_stiffness

#include "replay_summary.hpp"  // NOLINT(build/include_subdir)

#include <cstdio>
#include <optional>

#include "drivetrain_stiffness/core/validation.hpp"
#include "bag/replay_input.hpp"  // NOLINT(build/include_subdir): topicMatches

namespace drivetrain_stiffness {
namespace {

constexpr InputStream kStreams[] = {InputStream::kTorque, InputStream::kPreload,
                                    InputStream::kJointStates, InputStream::kVibration};
constexpr InputOutcome kRefusals[] = {InputOutcome::kWrongFrame,      InputOutcome::kInvalidValue,
                                      InputOutcome::kUnreachableLoad, InputOutcome::kZeroStamp,
                                      InputOutcome::kOutOfOrder,      InputOutcome::kStampRange};
/// Bag topics listed when a named topic is absent (a bag of a whole robot can hold hundreds).
constexpr std::size_t kMaxTopicsListed = 25;

std::uint64_t acceptedOn(InputStream s, const PipelineCounters& c) {
  switch (s) {
    case InputStream::kTorque: return c.accepted_torque;
    case InputStream::kPreload: return c.accepted_preload;
    case InputStream::kJointStates: return c.accepted_motion;
    case InputStream::kVibration: return c.accepted_vibration;
  }
  return 0;
}

std::uint64_t droppedOn(InputStream s, const PipelineCounters& c) {
  switch (s) {
    case InputStream::kTorque: return c.dropped_torque;
    case InputStream::kPreload: return c.dropped_preload;
    case InputStream::kJointStates: return c.dropped_motion;
    case InputStream::kVibration: return c.dropped_vibration;
  }
  return 0;
}

std::string stampText(Stamp s) {
  char text[40];
  std::snprintf(text, sizeof text, "%lld.%09lld s", static_cast<long long>(s.sec()),
                static_cast<long long>(s.nsec()));
  return text;
}

std::string foundText(const RefusalTally::Entry& e) {
  std::string text;
  for (const RefusalTally::Found& f : e.found) {
    text += (text.empty() ? "" : ", ") + ("'" + f.value + "' (" + std::to_string(f.count) + ")");
  }
  if (e.found_other > 0) text += ", " + std::to_string(e.found_other) + " with other values";
  return text;
}

bool typeWanted(const BagTopic& t, const ReplayInputTopic& input) {
  return t.type == input.expected_type;
}

/// The sentences of the summary, one per line; `bullet` starts each detail line.
/// The bag's message count on `topic` (as named, with or without the leading '/'); nullopt if
/// absent.
std::optional<std::uint64_t> inBag(const std::string& topic,
                                   const std::vector<BagTopic>& bag_topics) {
  std::optional<std::uint64_t> n;
  for (const BagTopic& t : bag_topics) {
    if (topicMatches(t.topic, topic)) n = n.value_or(0) + t.messages;
  }
  return n;
}

std::vector<std::string> sentences(const std::array<ReplayInputTopic, kInputStreams>& inputs,
                                   const RigPipeline& pipeline,
                                   const std::vector<BagTopic>& bag_topics,
                                   const std::string& bullet, bool damaged) {
  std::vector<std::string> out;
  const PipelineCounters& c = pipeline.counters();
  bool list_topics = false;
  for (const ReplayInputTopic& in : inputs) {
    const std::string head = std::string(toString(in.stream)) + " on '" + printableText(in.topic) +
                             "' (" + in.expected_type + ", " + in.option + "): ";
    const std::optional<std::uint64_t> held = inBag(in.topic, bag_topics);
    if (in.read == 0 && held) {
      out.push_back(head + std::to_string(*held) + " in the bag, none read" +
                    (damaged ? " before the damage" : ""));
      continue;
    }
    if (in.read == 0) {
      // Torque drives everything; the preload (the gearbox's until one arrives) and the encoders
      // (the nominal speed without them) are optional. A topic of the type it wants is pointed
      // out, and the bag's topics are listed below.
      const bool required = in.stream == InputStream::kTorque;
      out.push_back(head + "not in the bag" + (required ? "" : " (optional)"));
      list_topics = true;
      for (const BagTopic& t : bag_topics) {
        if (typeWanted(t, in)) {
          out.push_back(bullet + "'" + printableText(t.topic) + "' holds " +
                        std::to_string(t.messages) + " " + in.expected_type +
                        " messages: " + in.option + " " + printableText(t.topic) + " reads them");
        }
      }
      continue;
    }
    const std::uint64_t refused = pipeline.refusals().total(in.stream);
    out.push_back(
        head + std::to_string(in.read) + " read, " + std::to_string(acceptedOn(in.stream, c)) +
        " accepted, " + std::to_string(refused) + " refused" +
        (in.wrongType() ? ", " + std::to_string(in.wrongType()) + " of another type" : ""));
    for (const InputOutcome why : kRefusals) {
      const RefusalTally::Entry& e = pipeline.refusals().entry(in.stream, why);
      if (e.count == 0) continue;
      std::string line = bullet + std::to_string(e.count) + " refused (" + toString(why) + ")";
      if (!e.found.empty()) line += ", found " + foundText(e);
      out.push_back(line + "; the first, stamped " + stampText(e.first_stamp) + ": " +
                    e.first_reason);
    }
    for (const auto& [type, n] : in.wrong_types) {
      out.push_back(bullet + std::to_string(n) + " of type " + printableText(type) + ", not " +
                    in.expected_type + ": not read");
    }
    if (const std::uint64_t dropped = droppedOn(in.stream, c)) {
      out.push_back(bullet + std::to_string(dropped) +
                    " numbered by their publisher never reached the bag (header.seq gaps)");
    }
  }
  if (list_topics) {
    out.push_back("the bag's topics (" + std::to_string(bag_topics.size()) + "):");
    for (std::size_t i = 0; i < bag_topics.size() && i < kMaxTopicsListed; ++i) {
      const BagTopic& t = bag_topics[i];
      out.push_back(bullet + "'" + printableText(t.topic) + "' " + printableText(t.type) + ", " +
                    std::to_string(t.messages) + " messages");
    }
    if (bag_topics.size() > kMaxTopicsListed) {
      out.push_back(bullet + "and " + std::to_string(bag_topics.size() - kMaxTopicsListed) +
                    " more");
    }
  }
  return out;
}

}  // namespace

std::uint64_t ReplayInputTopic::wrongType() const {
  std::uint64_t n = 0;
  for (const auto& [type, count] : wrong_types) n += count;
  return n;
}

ReplaySummary::ReplaySummary(const std::array<std::string, kInputStreams>& topics)
    : inputs_{{{InputStream::kTorque,
                "--torque-topic",
                topics[0],
                "geometry_msgs/WrenchStamped",
                0,
                {}},
               {InputStream::kPreload,
                "--preload-topic",
                topics[1],
                "drivetrain_stiffness/Preload",
                0,
                {}},
               {InputStream::kJointStates,
                "--joint-states-topic",
                topics[2],
                "sensor_msgs/JointState",
                0,
                {}},
               {InputStream::kVibration,
                "--vibration-topic",
                topics[3],
                "drivetrain_stiffness/VibrationBlock",
                0,
                {}}}} {}

void ReplaySummary::requireDistinctTopics() const {
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    if (inputs_[i].topic.empty())
      throw InvalidInput(inputs_[i].option + " = '': a topic name is needed");
    for (std::size_t j = i + 1; j < inputs_.size(); ++j) {
      if (topicMatches(inputs_[i].topic, inputs_[j].topic)) {
        throw InvalidInput(inputs_[i].option + " = '" + inputs_[i].topic + "' and " +
                           inputs_[j].option + " = '" + inputs_[j].topic +
                           "' name one topic for two inputs; each input needs its own");
      }
    }
  }
}

void ReplaySummary::read(InputStream stream, const std::string& type) {
  ReplayInputTopic& in = input(stream);
  ++in.read;
  if (!type.empty()) ++in.wrong_types[type];
}

std::uint64_t ReplaySummary::wrongType() const {
  std::uint64_t n = 0;
  for (const ReplayInputTopic& in : inputs_) n += in.wrongType();
  return n;
}

std::uint64_t ReplaySummary::accepted(const PipelineCounters& c) {
  return c.accepted_torque + c.accepted_preload + c.accepted_motion + c.accepted_vibration;
}

nlohmann::json ReplaySummary::json(const RigPipeline& pipeline,
                                   const std::vector<BagTopic>& bag_topics) const {
  nlohmann::json j;
  const PipelineCounters& c = pipeline.counters();
  for (const ReplayInputTopic& in : inputs_) {
    nlohmann::json t = {{"topic", printableText(in.topic)},
                        {"type", in.expected_type},
                        {"in_bag", in.read > 0 || inBag(in.topic, bag_topics).has_value()},
                        {"read", in.read},
                        {"accepted", acceptedOn(in.stream, c)},
                        {"refused", pipeline.refusals().total(in.stream)},
                        {"dropped", droppedOn(in.stream, c)}};
    t["refused_by_reason"] = nlohmann::json::object();
    for (const InputOutcome why : kRefusals) {
      const RefusalTally::Entry& e = pipeline.refusals().entry(in.stream, why);
      if (e.count == 0) continue;
      nlohmann::json r = {{"count", e.count},
                          {"first_stamp", e.first_stamp.toSec()},
                          {"first_reason", e.first_reason}};
      r["found"] = nlohmann::json::object();
      for (const RefusalTally::Found& f : e.found) r["found"][f.value] = f.count;
      r["found_other"] = e.found_other;
      t["refused_by_reason"][toString(why)] = r;
    }
    t["wrong_type"] = nlohmann::json::object();
    for (const auto& [type, n] : in.wrong_types) t["wrong_type"][printableText(type)] = n;
    j[toString(in.stream)] = t;
  }
  j["bag_topics"] = nlohmann::json::array();
  for (const BagTopic& t : bag_topics) {
    j["bag_topics"].push_back({{"topic", printableText(t.topic)},
                               {"type", printableText(t.type)},
                               {"messages", t.messages}});
  }
  return j;
}

std::string ReplaySummary::text(const RigPipeline& pipeline,
                                const std::vector<BagTopic>& bag_topics) const {
  std::string text;
  for (const std::string& line : sentences(inputs_, pipeline, bag_topics, "    ", damaged_))
    text += "  " + line + "\n";
  return text;
}

std::string ReplaySummary::markdown(const RigPipeline& pipeline,
                                    const std::vector<BagTopic>& bag_topics) const {
  std::string md;
  for (const std::string& line : sentences(inputs_, pipeline, bag_topics, "  - ", damaged_)) {
    md += (line.rfind("  - ", 0) == 0 ? line : "- " + line) + "\n";
  }
  return md;
}

std::string ReplaySummary::wrongTypeText() const {
  std::string text;
  for (const ReplayInputTopic& in : inputs_) {
    for (const auto& [type, n] : in.wrong_types) {
      text += std::string(toString(in.stream)) + " topic '" + printableText(in.topic) + "' (" +
              in.option + "): " + std::to_string(n) + " messages of type " + printableText(type) +
              ", expected " + in.expected_type + "\n";
    }
  }
  return text;
}

}  // namespace drivetrain_stiffness

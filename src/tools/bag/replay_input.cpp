#include "replay_input.hpp"  // NOLINT(build/include_subdir)

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <type_traits>

#include <boost/make_shared.hpp>
#include <ros/serialization.h>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

/// A connection header's field, by reference into the header (which outlives the messages); "" if
/// absent.
const std::string& headerField(const std::map<std::string, std::string>* header, const char* name) {
  static const std::string kNone;
  if (!header) return kNone;
  const auto it = header->find(name);
  return it == header->end() ? kNone : it->second;
}

/// The file's first line (at most 32 characters). Throws InvalidInput naming the path if it is not
/// a readable regular file, saying what it is instead.
std::string firstLine(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  const std::string option = "--bag = '" + path + "': ";
  if (!fs::exists(status))
    throw InvalidInput(option + "no such file" + (ec ? " (" + ec.message() + ")" : ""));
  if (fs::is_directory(status)) throw InvalidInput(option + "a directory, not a bag file");
  if (!fs::is_regular_file(status))
    throw InvalidInput(option + "not a regular file (a device, pipe or socket)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(option + "cannot be read: " + std::strerror(errno));
  std::string line(32, '\0');
  in.read(line.data(), static_cast<std::streamsize>(line.size()));
  line.resize(static_cast<std::size_t>(in.gcount()));
  return line.substr(0, line.find('\n'));
}

std::string recordTime(const ros::Time& t) {
  char s[32];
  std::snprintf(s, sizeof s, "%u.%09u", t.sec, t.nsec);
  return s;
}

template <class T>
constexpr MessageLayout layoutOf();
template <>
constexpr MessageLayout layoutOf<geometry_msgs::WrenchStamped>() {
  return MessageLayout::kWrenchStamped;
}
template <>
constexpr MessageLayout layoutOf<drivetrain_stiffness::Preload>() {
  return MessageLayout::kPreload;
}
template <>
constexpr MessageLayout layoutOf<sensor_msgs::JointState>() {
  return MessageLayout::kJointState;
}
template <>
constexpr MessageLayout layoutOf<drivetrain_stiffness::VibrationBlock>() {
  return MessageLayout::kVibrationBlock;
}

template <class T>
bool hasTypeOf(const BagConnection& connection) {
  const std::string md5sum = ros::message_traits::MD5Sum<T>::value();
  return md5sum == "*" || md5sum == connection.field("md5sum");
}

/// The recorded message as T, as MessageInstance::instantiate does it: null if the MD5 sums differ.
/// Throws InvalidInput if its bytes do not hold a T (checked before deserializing).
template <class T>
boost::shared_ptr<T> deserialize(const BagRecordMessage& raw) {
  if (!hasTypeOf<T>(*raw.connection)) return {};
  const std::string bad = checkSerializedMessage(layoutOf<T>(), raw.data, raw.size);
  if (!bad.empty()) throw InvalidInput(bad);
  auto message = boost::make_shared<T>();
  ros::serialization::IStream stream(const_cast<std::uint8_t*>(raw.data), raw.size);
  ros::serialization::deserialize(stream, *message);
  return message;
}

/// The layout of T when the connection records a T, else none (the loop counts a wrong type).
template <class T>
std::optional<MessageLayout> layoutIfTypeOf(const BagConnection& connection) {
  if (!hasTypeOf<T>(connection)) return std::nullopt;
  return layoutOf<T>();
}

}  // namespace

bool topicMatches(const std::string& topic, const std::string& wanted) {
  // Equal, or equal but for one leading '/' on one side; without building strings: it runs twice
  // per message.
  const std::string_view t(topic), w(wanted);
  return t == w || (!t.empty() && t[0] == '/' && t.substr(1) == w) ||
         (!w.empty() && w[0] == '/' && w.substr(1) == t);
}

ReplayInput::ReplayInput(const std::string& path, const ReplayTopics& topics)
    : path_(path), topics_(topics) {
  const std::string version = firstLine(path);
  if (version.rfind("#ROSBAG V", 0) != 0)
    throw InvalidInput("--bag = '" + path +
                       "': not a ROS bag (it does not start with '#ROSBAG V')");
  if (version != "#ROSBAG V2.0") {
    throw InvalidInput(
        "--bag = '" + path + "': a bag of format " + version.substr(9) +
        "; only format 2.0 is read (`rosbag filter OLD.bag NEW.bag True` writes a copy in 2.0)");
  }
  check_ = checkBagIndex(path, [this](const BagConnection& c) { return readRule(c); });
  if (check_.usable) {
    try {
      bag_ = std::make_unique<rosbag::Bag>();
      bag_->open(path, rosbag::bagmode::Read);
      view_ = std::make_unique<rosbag::View>(
          *bag_, [this](const rosbag::ConnectionInfo* c) { return isWanted(c->topic); });
      return;
    } catch (const std::exception&
                 e) {  // rosbag::BagException: a bag the check passed and rosbag refuses
      index_unusable_ = std::string("rosbag::Bag cannot open it: ") + e.what();
      view_.reset();
      bag_.reset();
    }
  } else {
    index_unusable_ = check_.index_damage->describe(path);
  }
  sequential_ = std::make_unique<SequentialBagReader>(path);
}

ReadRule ReplayInput::readRule(const BagConnection& connection) const {
  ReadRule rule;
  rule.read = isWanted(connection.topic);
  if (!rule.read) return rule;
  switch (*streamOf(connection.topic)) {
    case InputStream::kTorque:
      rule.layout = layoutIfTypeOf<geometry_msgs::WrenchStamped>(connection);
      break;
    case InputStream::kPreload:
      rule.layout = layoutIfTypeOf<drivetrain_stiffness::Preload>(connection);
      break;
    case InputStream::kJointStates:
      rule.layout = layoutIfTypeOf<sensor_msgs::JointState>(connection);
      break;
    case InputStream::kVibration:
      rule.layout = layoutIfTypeOf<drivetrain_stiffness::VibrationBlock>(connection);
      break;
  }
  return rule;
}

std::vector<BagTopic> ReplayInput::topics() const {
  if (!sequential_) return check_.topics;
  std::vector<BagTopic> topics;
  for (const auto& [id, c] : sequential_->connections())
    topics.push_back({c.topic, c.field("type"), c.field("md5sum"), c.messages});
  return topics;
}

ReplayInput::Iterator ReplayInput::begin() {
  if (!begun_) {
    begun_ = true;
    advance();
  }
  return Iterator(*this);
}

void ReplayInput::advance() {
  has_message_ = !damage_ && (view_ ? nextIndexed() : nextSequential());
  if (has_message_) ++read_;
}

template <class Make>
void ReplayInput::fill(ReplayMessage& message, InputStream stream, const Make& make) {
  // The type follows the topic: each stream's message type, the others null.
  const auto of = [&](InputStream wanted, auto* type) {
    return stream == wanted ? make(type) : nullptr;
  };
  message.torque_ = of(InputStream::kTorque, static_cast<geometry_msgs::WrenchStamped*>(nullptr));
  message.preload_ =
      of(InputStream::kPreload, static_cast<drivetrain_stiffness::Preload*>(nullptr));
  message.joint_states_ =
      of(InputStream::kJointStates, static_cast<sensor_msgs::JointState*>(nullptr));
  message.vibration_ =
      of(InputStream::kVibration, static_cast<drivetrain_stiffness::VibrationBlock*>(nullptr));
}

std::optional<InputStream> ReplayInput::streamOf(const std::string& topic) const {
  for (const InputStream s : {InputStream::kTorque, InputStream::kJointStates,
                              InputStream::kVibration, InputStream::kPreload}) {
    if (topicMatches(topic, topics_[static_cast<std::size_t>(s)])) return s;
  }
  return std::nullopt;
}

bool ReplayInput::nextIndexed() {
  try {
    if (read_ == 0) {
      view_next_ = view_->begin();
      view_end_ = view_->end();
    } else {
      ++view_next_;
    }
    if (view_next_ == view_end_) return false;
    const rosbag::MessageInstance& m = *view_next_;
    if (check_.stop && m.getTime() >= *check_.stop) {  // the first message the check found damaged
      damage_ = check_.damage;
      return false;
    }
    message_.time_ = m.getTime();
    message_.topic_ = &m.getTopic();
    message_.caller_id_ = &headerField(m.getConnectionHeader().get(), "callerid");
    message_.data_type_ = &m.getDataType();
    fill(message_, *streamOf(m.getTopic()),
         [&](auto* type) { return m.instantiate<std::remove_pointer_t<decltype(type)>>(); });
    return true;
  } catch (
      const std::exception& e) {  // a chunk that does not decompress, a damaged record or message
    damage_ = locateDamage(e.what());
    return false;
  }
}

bool ReplayInput::nextSequential() {
  BagRecordMessage raw;
  while (sequential_->next(raw)) {
    if (!isWanted(raw.connection->topic)) continue;
    try {
      decode(raw, message_);
      return true;
    } catch (const std::exception& e) {
      damage_ =
          BagDamage{raw.offset, "the " + raw.connection->topic + " message at record time " +
                                    recordTime(raw.time) + " does not deserialize: " + e.what() +
                                    "; " + withoutIndex()};
      return false;
    }
  }
  damage_ = endOfSequentialReading();
  return false;
}

std::string ReplayInput::withoutIndex() const {
  return "read without the index (" + index_unusable_ + ")";
}

void ReplayInput::decode(const BagRecordMessage& raw, ReplayMessage& message) const {
  message.time_ = raw.time;
  message.topic_ = &raw.connection->topic;
  message.caller_id_ = &headerField(&raw.connection->header, "callerid");
  message.data_type_ = &headerField(&raw.connection->header, "type");
  fill(message, *streamOf(raw.connection->topic),
       [&](auto* type) { return deserialize<std::remove_pointer_t<decltype(type)>>(raw); });
}

/// A sequential reading ends in damage: the reader's, or (every chunk read whole) the index that
/// rosbag could not read.
BagDamage ReplayInput::endOfSequentialReading() const {
  if (const auto& damage = sequential_->damage())
    return BagDamage{damage->offset, damage->what + "; " + withoutIndex()};
  return BagDamage{
      sequential_->indexPosition(),
      "every chunk reads whole, so the index from this byte is damaged; " + withoutIndex()};
}

/// rosbag::View failed on message read_ + 1: where is the damage? Reads the bag sequentially up to
/// the first record that fails to read or to deserialize as the loop would.
BagDamage ReplayInput::locateDamage(const std::string& rosbag_error) const {
  const std::string topic = message_.topic_ ? *message_.topic_ : std::string("?");
  const std::string failed = "rosbag::View cannot read message " + std::to_string(read_ + 1) +
                             " (" + topic + " at record time " + recordTime(message_.time_) +
                             "): " + rosbag_error;
  try {
    SequentialBagReader reader(path_);
    BagRecordMessage raw;
    ReplayMessage scratch;
    while (reader.next(raw)) {
      if (!isWanted(raw.connection->topic)) continue;
      try {
        decode(raw, scratch);
      } catch (const std::exception& e) {
        return BagDamage{raw.offset, "the " + raw.connection->topic + " message at record time " +
                                         recordTime(raw.time) +
                                         " does not deserialize: " + e.what() + "; " + failed};
      }
    }
    if (const auto& damage = reader.damage())
      return BagDamage{damage->offset, damage->what + "; " + failed};
    return BagDamage{
        reader.indexPosition(),
        failed +
            "; every chunk reads whole without the index, so the index from this byte is damaged"};
  } catch (const InvalidInput& e) {  // not format 2.0
    return BagDamage{0, failed + "; byte offset unknown: " + e.what()};
  }
}

}  // namespace drivetrain_stiffness

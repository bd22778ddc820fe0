#include "message_layout.hpp"  // NOLINT(build/include_subdir)

#include <cstring>

namespace drivetrain_stiffness {
namespace {

/// Walks serialized fields; the first field that does not fit sets `error` and stops the walk.
class Cursor {
 public:
  Cursor(const std::uint8_t* data, std::size_t size) : p_(data), left_(size) {}

  bool fixed(std::size_t n, const char* field) {
    if (!ok()) return false;
    if (n > left_)
      return fail(field, std::to_string(n) + " bytes, " + std::to_string(left_) + " left");
    p_ += n;
    left_ -= n;
    return true;
  }
  bool string(const char* field) {
    std::uint32_t n = 0;
    return length(field, n) && fixed(n, field);
  }
  /// A variable array of fixed-size elements (float64[]: 8 bytes each).
  bool fixedArray(const char* field, std::size_t element) {
    std::uint32_t n = 0;
    if (!length(field, n)) return false;
    if (std::uint64_t{n} * element > left_) return tooLong(field, n, element);
    return fixed(n * element, field);
  }
  /// A variable array whose elements take at least `least` bytes each, walked by `each`.
  template <typename Each>
  bool array(const char* field, std::size_t least, Each each) {
    std::uint32_t n = 0;
    if (!length(field, n)) return false;
    if (std::uint64_t{n} * least > left_) return tooLong(field, n, least);
    for (std::uint32_t i = 0; i < n && ok(); ++i) each(*this);
    return ok();
  }
  bool header() {
    return fixed(4, "header.seq") && fixed(8, "header.stamp") && string("header.frame_id");
  }
  std::string finish() {
    if (ok() && left_ > 0) error_ = std::to_string(left_) + " bytes left over after the last field";
    return error_;
  }

 private:
  bool ok() const { return error_.empty(); }
  bool fail(const char* field, const std::string& what) {
    if (ok()) error_ = std::string(field) + ": " + what;
    return false;
  }
  bool length(const char* field, std::uint32_t& n) {
    if (!ok()) return false;
    if (left_ < 4)
      return fail(field, "its length is cut off (" + std::to_string(left_) + " of 4 bytes)");
    std::memcpy(&n, p_, 4);
    p_ += 4;
    left_ -= 4;
    return true;
  }
  bool tooLong(const char* field, std::uint32_t n, std::size_t least) {
    return fail(field, "claims " + std::to_string(n) + " elements of at least " +
                           std::to_string(least) + " bytes, " + std::to_string(left_) +
                           " bytes left");
  }

  const std::uint8_t* p_;
  std::size_t left_;
  std::string error_;
};

}  // namespace

std::string checkSerializedMessage(MessageLayout layout, const std::uint8_t* data,
                                   std::size_t size) {
  // Field order and types: geometry_msgs/WrenchStamped, sensor_msgs/JointState,
  // drivetrain_stiffness/Preload (msg/Preload.msg, msg/BearingPreload.msg),
  // drivetrain_stiffness/VibrationBlock (msg/VibrationBlock.msg).
  Cursor c(data, size);
  c.header();
  switch (layout) {
    case MessageLayout::kWrenchStamped: c.fixed(6 * 8, "wrench"); break;
    case MessageLayout::kJointState:
      c.array("name", 4, [](Cursor& e) { e.string("name[]"); });
      c.fixedArray("position", 8);
      c.fixedArray("velocity", 8);
      c.fixedArray("effort", 8);
      break;
    case MessageLayout::kPreload:
      c.array("bearings", 4 + 4 * 8,
              [](Cursor& e) { e.string("bearings[].name") && e.fixed(4 * 8, "bearings[]"); });
      break;
    case MessageLayout::kVibrationBlock:
      c.fixed(8, "sample_rate");
      c.array("channels", 4, [](Cursor& e) { e.string("channels[]"); });
      c.fixedArray("data", 4);
      break;
  }
  return c.finish();
}

}  // namespace drivetrain_stiffness

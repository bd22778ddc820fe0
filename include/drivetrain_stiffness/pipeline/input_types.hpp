// The pipeline's input vocabulary: stamps, origins, refusal reasons.
#pragma once

#include <cstdint>
#include <string_view>

namespace drivetrain_stiffness {

/// Integer nanoseconds since the caller's epoch: exact differences; toSec() as ros::Time's.
struct Stamp {
  std::int64_t ns = 0;
  static Stamp fromSecNsec(std::int64_t sec, std::int64_t nsec) {
    return {sec * 1000000000LL + nsec};
  }
  std::int64_t sec() const { return ns / 1000000000LL; }
  std::int64_t nsec() const { return ns % 1000000000LL; }
  double toSec() const { return static_cast<double>(sec()) + 1e-9 * static_cast<double>(nsec()); }
  bool isZero() const { return ns == 0; }
  /// ros::Time's range (1970 to 2106-02-07).
  static constexpr std::int64_t kMaxRosNs = 4294967295LL * 1000000000LL + 999999999LL;
  bool inRosRange() const { return ns >= 0 && ns <= kMaxRosNs; }
};
inline bool operator<(Stamp a, Stamp b) { return a.ns < b.ns; }
inline bool operator==(Stamp a, Stamp b) { return a.ns == b.ns; }
/// Exact difference a - b [s].
inline double secondsBetween(Stamp a, Stamp b) { return Stamp{a.ns - b.ns}.toSec(); }

/// Why an input was not accepted (kAccepted otherwise).
enum class InputOutcome {
  kAccepted,
  kZeroStamp,
  kOutOfOrder,
  kInvalidValue,
  kUnreachableLoad,
  kWrongFrame,
  kStampRange
};
const char* toString(InputOutcome outcome);

/// Where an input came from, for the drop count and the frame rule.
struct InputOrigin {
  std::string_view publisher;  ///< caller id
  std::uint32_t seq = 0;       ///< header.seq
  std::string_view frame_id;   ///< header.frame_id
};

/// Whether the subscriber queue holds a backlog at this input (the transport rules).
enum class Backlog { kNone, kShed };

}  // namespace drivetrain_stiffness

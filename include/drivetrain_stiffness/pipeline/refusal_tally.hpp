// Every input the pipeline refused, per stream and reason, with what was found.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "drivetrain_stiffness/pipeline/input_types.hpp"

namespace drivetrain_stiffness {

/// The pipeline's input streams.
enum class InputStream { kTorque, kPreload, kJointStates, kVibration };
constexpr std::size_t kInputStreams = 4;
/// "torque", "preload", "joint_states", "vibration": the topic names the pipeline's messages use.
const char* toString(InputStream stream);

class RefusalTally {
 public:
  /// Distinct found values kept per stream and reason; further ones are counted together.
  static constexpr std::size_t kMaxFound = 8;
  struct Found {
    std::string value;  ///< printable (printableText)
    std::uint64_t count = 0;
  };
  /// The refusals of one stream for one reason.
  struct Entry {
    std::uint64_t count = 0;
    Stamp first_stamp;
    std::string first_reason;
    std::vector<Found> found;       ///< by first appearance
    std::uint64_t found_other = 0;  ///< beyond kMaxFound
  };

  /// Counts one refusal; `found` (may be empty): the offending value.
  void record(InputStream stream, InputOutcome why, Stamp stamp, std::string_view reason,
              std::string_view found = {});
  const Entry& entry(InputStream stream, InputOutcome why) const;
  /// Refusals of `stream` for every reason.
  std::uint64_t total(InputStream stream) const;

 private:
  static constexpr std::size_t kOutcomes = static_cast<std::size_t>(InputOutcome::kStampRange) + 1;
  std::array<std::array<Entry, kOutcomes>, kInputStreams> entries_{};
};

}  // namespace drivetrain_stiffness

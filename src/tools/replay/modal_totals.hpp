// A recording's modal identifications summed over the bag for summary.json (docs/tools.md
// "drivetrain_replay", `modal`).
#pragma once

#include <array>
#include <cstdint>

#include <nlohmann/json.hpp>

#include <drivetrain_stiffness/ModalIdentification.h>

namespace drivetrain_stiffness {

class ModalTotals {
 public:
  /// Counts the record and keeps, per dominant coordinate of a matched model mode, its identified
  /// frequency [Hz] and standard deviation [Hz]; a later record replaces an earlier one's.
  void add(const drivetrain_stiffness::ModalIdentification& m);

  /// records; per dominant coordinate ("x_p", "x_g", "x"): identified (records that matched it),
  /// frequency [Hz], frequency_std [Hz] (null: not computed), stamp [s since the epoch],
  /// model_mode and unresolved of the last record that matched it; null figures without one.
  nlohmann::json json() const;

 private:
  struct Last {
    std::uint64_t identified = 0;
    double frequency = 0.0, frequency_std = 0.0, stamp = 0.0;
    int model_mode = -1;
    bool unresolved = false;
  };
  std::uint64_t records_ = 0;
  std::array<Last, 3> last_{};  ///< by kCoordinates
};

}  // namespace drivetrain_stiffness

#include "modal_totals.hpp"  // NOLINT(build/include_subdir)

#include <string>

namespace drivetrain_stiffness {
namespace {

/// The model's coordinates, as PredictedMode.dominant names them
/// (core/resonance/modal_analysis.cpp).
constexpr const char* kCoordinates[3] = {"x_p", "x_g", "x"};

int coordinate(const std::string& name) {
  for (int i = 0; i < 3; ++i) {
    if (name == kCoordinates[i]) return i;
  }
  return -1;
}

}  // namespace

void ModalTotals::add(const drivetrain_stiffness::ModalIdentification& m) {
  ++records_;
  // Identified modes in frequency order: when two model modes share a dominant coordinate in one
  // record, the higher one's stays, and the record counts once.
  std::array<bool, 3> seen{};
  for (const drivetrain_stiffness::IdentifiedMode& x : m.modes) {
    if (x.model_mode < 0 || static_cast<std::size_t>(x.model_mode) >= m.predicted.size()) continue;
    const int c = coordinate(m.predicted[static_cast<std::size_t>(x.model_mode)].dominant);
    if (c < 0) continue;
    Last& last = last_[static_cast<std::size_t>(c)];
    if (!seen[static_cast<std::size_t>(c)]) ++last.identified;
    seen[static_cast<std::size_t>(c)] = true;
    last.frequency = x.frequency;
    last.frequency_std = x.frequency_std;
    last.stamp = m.header.stamp.toSec();
    last.model_mode = x.model_mode;
    last.unresolved = x.unresolved;
  }
}

nlohmann::json ModalTotals::json() const {
  nlohmann::json j;
  j["records"] = records_;
  for (std::size_t c = 0; c < last_.size(); ++c) {
    const Last& last = last_[c];
    const bool any = last.identified > 0;
    auto value = [&](auto v) { return any ? nlohmann::json(v) : nlohmann::json(nullptr); };
    j["modes"][kCoordinates[c]] = {
        {"identified", last.identified},
        {"frequency", value(last.frequency)},
        // IdentifiedMode.frequency_std: 0 when it was not computed.
        {"frequency_std", any && last.frequency_std > 0.0 ? nlohmann::json(last.frequency_std)
                                                          : nlohmann::json(nullptr)},
        {"stamp", value(last.stamp)},
        {"model_mode", value(last.model_mode)},
        {"unresolved", value(last.unresolved)}};
  }
  return j;
}

}  // namespace drivetrain_stiffness

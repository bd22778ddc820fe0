#include "drivetrain_stiffness/pipeline/vibration_channels.hpp"

#include <algorithm>

#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

std::vector<VibrationChannelAlias> parseVibrationAliases(
    const std::map<std::string, std::string>& entries) {
  std::vector<VibrationChannelAlias> aliases;
  for (const auto& [name, support] : entries) {
    const bool against = !support.empty() && support.front() == '-';
    aliases.push_back({name, against ? support.substr(1) : support, against ? -1.0 : 1.0});
  }
  return aliases;
}

std::vector<VibrationChannel> vibrationChannels(const RigConfig& rig,
                                                const std::vector<VibrationChannelAlias>& aliases) {
  std::vector<VibrationChannel> map;
  for (const BearingSupportConfig& b : rig.bearings) map.push_back({b.name, b.shaft, 1.0});
  for (const VibrationChannelAlias& a : aliases) {
    const std::string field = "vibration_channels[" + printableText(a.name) + "]";
    if (a.name.empty()) throw InvalidInput("vibration_channels: a channel name is empty");
    for (const VibrationChannel& m : map) {
      if (m.name == a.name) throw InvalidInput(field + ": the name is mapped already");
    }
    if (a.sign != 1.0 && a.sign != -1.0) throwInvalid(field + ".sign", a.sign, "must be 1 or -1");
    const auto support =
        std::find_if(rig.bearings.begin(), rig.bearings.end(),
                     [&](const BearingSupportConfig& b) { return b.name == a.support; });
    if (support == rig.bearings.end()) {
      std::string known;
      for (const BearingSupportConfig& b : rig.bearings)
        known += (known.empty() ? "" : ", ") + b.name;
      throw InvalidInput(field + ".support = " + "'" + printableText(a.support) + "'" +
                         ": not a bearing support of the gearbox (" + known + ")");
    }
    map.push_back({a.name, support->shaft, a.sign});
  }
  return map;
}

}  // namespace drivetrain_stiffness

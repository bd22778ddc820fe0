#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace drivetrain_stiffness {

/// The recorded input types drivetrain_replay deserializes.
enum class MessageLayout { kWrenchStamped, kPreload, kJointState, kVibrationBlock };

/// "" if [data, data + size) holds exactly one ROS 1 serialized `layout` message whose every length
/// fits the bytes that follow it; otherwise what is wrong, naming the field.
std::string checkSerializedMessage(MessageLayout layout, const std::uint8_t* data,
                                   std::size_t size);

}  // namespace drivetrain_stiffness

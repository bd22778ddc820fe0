// Checks a serialized input message against its type's layout before ROS deserializes it:
// roscpp_serialization resizes an array to the length it reads before it checks that the bytes
// are there, so one damaged length in a recorded JointState asks for billions of elements.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace drivetrain_stiffness {

/// The recorded input types drivetrain_replay deserializes.
enum class MessageLayout { kWrenchStamped, kPreload, kJointState, kVibrationBlock };

/// "" if [data, data + size) holds exactly one message of `layout` (ROS 1 serialization: uint32
/// lengths before every string and variable array, little-endian), every length within the bytes
/// that follow it; otherwise what is wrong, naming the field.
std::string checkSerializedMessage(MessageLayout layout, const std::uint8_t* data,
                                   std::size_t size);

}  // namespace drivetrain_stiffness

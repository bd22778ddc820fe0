// Input validation shared by every core class: each check throws InvalidInput with a message
// that names the field and the offending value, so a bad YAML key or a bad topic value is
// reported precisely instead of surfacing later as a NaN.
#pragma once

#include <cmath>
#include <string>
#include <string_view>

#include "drivetrain_stiffness/core/errors.hpp"  // InvalidInput, UnreachableLoad

namespace drivetrain_stiffness {

/// Formats a double with enough digits to reproduce it (used in every error message).
std::string formatValue(double value);

/// Text from outside (a frame id, a joint or topic name read from a message or a bag) made safe for
/// messages, the console, JSON and CSV: printable ASCII kept, every other byte as \xNN, a
/// backslash as \\. Valid UTF-8 output whatever bytes came in.
std::string printableText(std::string_view text);

/// Throws InvalidInput("<field> = <value>: <why>").
[[noreturn]] void throwInvalid(const std::string& field, double value, const std::string& why);

/// Inline and taking a string_view: it runs once per sample in the streaming paths (spectra,
/// dynamics), where building the field's std::string on every call cost ~2 % of a replay.
[[noreturn]] void throwNotFinite(std::string_view field, double value);
inline void requireFinite(std::string_view field, double value) {
  if (!std::isfinite(value)) throwNotFinite(field, value);
}
// The checks take the field as a string_view: a name is built into a std::string only when the
// check fails, so checks on the per-input and per-window paths allocate nothing.
void requirePositive(std::string_view field, double value);
void requireNonNegative(std::string_view field, double value);
/// value <= limit, for magnitudes past anything physical: a value like 1e308 passes every sign
/// check and then overflows the model into NaN (found by fuzzing, test/fuzz/).
void requireAtMost(std::string_view field, double value, double limit);
/// Plausibility bounds shared by the core's checks (an order of magnitude past anything made).
constexpr double kMinYoungsModulus =
    1e6;  ///< [Pa] below elastomers; a subnormal one underflows to 0
constexpr double kMaxYoungsModulus = 1e13;  ///< [Pa] diamond is 1.2e12
/// kMinYoungsModulus <= value <= kMaxYoungsModulus.
void requireYoungsModulus(std::string_view field, double value);
/// lower < value < upper (open interval).
void requireInOpenRange(std::string_view field, double value, double lower, double upper);
/// lower <= value < upper.
void requireInHalfOpenRange(std::string_view field, double value, double lower, double upper);
/// lower <= value <= upper.
void requireInClosedRange(std::string_view field, double value, double lower, double upper);

}  // namespace drivetrain_stiffness

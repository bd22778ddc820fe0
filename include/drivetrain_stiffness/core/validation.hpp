// Input checks shared by the core: each throws InvalidInput naming the field and the value.
#pragma once

#include <cmath>
#include <string>
#include <string_view>

#include "drivetrain_stiffness/core/errors.hpp"  // InvalidInput, UnreachableLoad

namespace drivetrain_stiffness {

/// A double with enough digits to reproduce it.
std::string formatValue(double value);

/// Outside text as printable ASCII: other bytes as \xNN, a backslash as \\.
std::string printableText(std::string_view text);

/// Throws InvalidInput("<field> = <value>: <why>").
[[noreturn]] void throwInvalid(const std::string& field, double value, const std::string& why);

/// Throws InvalidInput naming a non-finite value (requireFinite's cold path).
[[noreturn]] void throwNotFinite(std::string_view field, double value);
inline void requireFinite(std::string_view field, double value) {
  if (!std::isfinite(value)) throwNotFinite(field, value);
}
/// Throw InvalidInput("<field> = <value>: ...") unless value > 0, value >= 0; allocation-free when
/// they pass.
void requirePositive(std::string_view field, double value);
void requireNonNegative(std::string_view field, double value);
/// value <= limit: a bound past anything physical that keeps the model from overflowing.
void requireAtMost(std::string_view field, double value, double limit);
constexpr double kMinYoungsModulus = 1e6;   ///< [Pa] below elastomers
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

#include "drivetrain_stiffness/core/validation.hpp"

#include <cmath>
#include <sstream>

namespace drivetrain_stiffness {

std::string formatValue(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

void throwInvalid(const std::string& field, double value, const std::string& why) {
  throw InvalidInput(field + " = " + formatValue(value) + ": " + why);
}

void throwNotFinite(std::string_view field, double value) {
  throwInvalid(std::string(field), value, "must be a finite number");
}

void requirePositive(std::string_view field, double value) {
  requireFinite(field, value);
  if (!(value > 0.0)) throwInvalid(std::string(field), value, "must be > 0");
}

void requireNonNegative(std::string_view field, double value) {
  requireFinite(field, value);
  if (value < 0.0) throwInvalid(std::string(field), value, "must be >= 0");
}

void requireAtMost(std::string_view field, double value, double limit) {
  requireFinite(field, value);
  if (value > limit) throwInvalid(std::string(field), value, "must be <= " + formatValue(limit));
}

void requireYoungsModulus(std::string_view field, double value) {
  requireFinite(field, value);
  if (!(value >= kMinYoungsModulus && value <= kMaxYoungsModulus)) {
    throwInvalid(std::string(field), value,
                 "must lie in [" + formatValue(kMinYoungsModulus) + ", " +
                     formatValue(kMaxYoungsModulus) + "] Pa");
  }
}

void requireInOpenRange(std::string_view field, double value, double lower, double upper) {
  requireFinite(field, value);
  if (!(value > lower && value < upper)) {
    throwInvalid(std::string(field), value,
                 "must lie in (" + formatValue(lower) + ", " + formatValue(upper) + ")");
  }
}

void requireInHalfOpenRange(std::string_view field, double value, double lower, double upper) {
  requireFinite(field, value);
  if (!(value >= lower && value < upper)) {
    throwInvalid(std::string(field), value,
                 "must lie in [" + formatValue(lower) + ", " + formatValue(upper) + ")");
  }
}

void requireInClosedRange(std::string_view field, double value, double lower, double upper) {
  requireFinite(field, value);
  if (!(value >= lower && value <= upper)) {
    throwInvalid(std::string(field), value,
                 "must lie in [" + formatValue(lower) + ", " + formatValue(upper) + "]");
  }
}

std::string printableText(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte == '\\') {
      out += "\\\\";
    } else if (byte >= 0x20 && byte < 0x7f) {
      out += c;
    } else {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 0xf];
    }
  }
  return out;
}

}  // namespace drivetrain_stiffness

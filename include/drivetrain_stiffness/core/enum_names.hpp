// One table per enum for its names in YAML, on the command line and in reports: parse and name
// read the same table, so the two can never disagree, and the error lists exactly what is accepted.
#pragma once

#include <cstddef>
#include <string>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

template <typename E>
struct EnumName {
  E value;
  const char* name;
};

/// The table's name for `value` ("?" for a value the table lacks).
template <typename E, std::size_t N>
const char* enumName(const EnumName<E> (&table)[N], E value) {
  for (const EnumName<E>& e : table) {
    if (e.value == value) return e.name;
  }
  return "?";
}

/// The value named `text`; InvalidInput "FIELD = 'TEXT': must be 'a', 'b' or 'c'" otherwise.
template <typename E, std::size_t N>
E parseEnum(const EnumName<E> (&table)[N], const std::string& field, const std::string& text) {
  for (const EnumName<E>& e : table) {
    if (text == e.name) return e.value;
  }
  std::string accepted;
  for (std::size_t i = 0; i < N; ++i) {
    accepted += (i == 0 ? "'" : i + 1 == N ? " or '" : ", '") + std::string(table[i].name) + "'";
  }
  throw InvalidInput(field + " = '" + text + "': must be " + accepted);
}

}  // namespace drivetrain_stiffness

// Reading private parameters once, at start-up, with clear errors: a parameter that is present but
// has the wrong type is an error naming it (roscpp's param() would silently fall back to the
// default), and an absent one takes the documented default.
#pragma once

#include <map>
#include <string>

#include <ros/node_handle.h>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

template <typename T>
const char* parameterTypeName();
template <>
inline const char* parameterTypeName<double>() {
  return "a number";
}
template <>
inline const char* parameterTypeName<int>() {
  return "an integer";
}
template <>
inline const char* parameterTypeName<bool>() {
  return "true or false";
}
template <>
inline const char* parameterTypeName<std::string>() {
  return "a string";
}

template <>
inline const char* parameterTypeName<std::map<std::string, std::string>>() {
  return "a map of strings to strings";
}

template <typename T>
T readParam(const ros::NodeHandle& pnh, const std::string& name, const T& fallback) {
  if (!pnh.hasParam(name)) return fallback;
  T value{};
  // getParam(double) also accepts integers (xml_castable), so "1" works where "1.0" is meant.
  if (!pnh.getParam(name, value)) {
    throw InvalidInput("~" + name + ": has the wrong type (expected " + parameterTypeName<T>() +
                       ")");
  }
  return value;
}

}  // namespace drivetrain_stiffness

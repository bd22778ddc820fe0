// The node's private parameters read from a parsed YAML map, as the parameter server would hand
// them to the node (ros/node_parameters.hpp's `get`): absent -> the fallback, present with the
// wrong type -> InvalidInput naming the parameter. drivetrain_replay --params and the fuzz harness
// read parameters through this one getter.
#pragma once

#include <string>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

class YamlParameters {
 public:
  explicit YamlParameters(YAML::Node root = YAML::Node()) : root_(std::move(root)) {}
  template <typename T>
  T operator()(const std::string& name, const T& fallback) const {
    if (!root_.IsMap() || !root_[name]) return fallback;
    try {
      return root_[name].as<T>();
    } catch (const YAML::Exception&) {
      throw InvalidInput("parameter ~" + name + ": has the wrong type");
    }
  }

 private:
  YAML::Node root_;
};

}  // namespace drivetrain_stiffness

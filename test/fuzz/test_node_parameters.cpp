// Refusals of the node's output parameters name the parameter (fuzz finding: a bad frame id was
// refused as "~*_frame", which does not say which of the three).
#include <gtest/gtest.h>

#include <map>
#include <type_traits>

#include "drivetrain_stiffness/ros/node_parameters.hpp"

using namespace drivetrain_stiffness;

namespace {

// A getter with only string parameters set; everything else takes its default.
struct StringParams {
  std::map<std::string, std::string> values;
  template <typename T>
  T operator()(const std::string& name, const T& fallback) const {
    if constexpr (std::is_same_v<T, std::string>) {
      const auto it = values.find(name);
      return it == values.end() ? fallback : it->second;
    } else {
      return fallback;
    }
  }
};

}  // namespace

TEST(NodeParameters, AFrameRefusalNamesTheFrame) {
  for (const std::string name : {"rig_frame", "pinion_frame", "gear_frame"}) {
    for (const std::string bad : {"", "/world"}) {
      try {
        readOutputSettings(StringParams{{{name, bad}}});
        ADD_FAILURE() << name << " = '" << bad << "' accepted";
      } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("~" + name + " = '" + bad + "'"), std::string::npos)
            << e.what();
      }
    }
  }
  EXPECT_EQ(readOutputSettings(StringParams{{{"gear_frame", "g"}}}).frames.gear, "g");
}

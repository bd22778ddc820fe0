// drivetrain_latency: loads a running stiffness_estimator with torque at ~rate [Hz] for ~duration
// [s] and prints, as JSON on stdout, the input-to-output latency percentiles (receipt - input stamp
// of each stiffness answer), the counts, and the node's own figures from /diagnostics (deadline
// misses, processing time, resident memory after ~warmup [s] and at the end).
// It must be the only torque (and preload) source of the node: answers are counted, not matched.
// Run it with launch/latency.launch (or scripts/soak). Messages go to stderr (ROS_WARN and above),
// so stdout is JSON; ~out names a file for the same JSON.
#include <fstream>
#include <iostream>

#include "drivetrain_stiffness/ros/parameters.hpp"
#include "load_generator.hpp"

using namespace drivetrain_stiffness;

int main(int argc, char** argv) {
  ros::init(argc, argv, "drivetrain_latency");
  ros::NodeHandle nh, pnh("~");
  LoadOptions options;
  std::string out;  // also write the JSON here (scripts/soak reads it; roslaunch mixes stdout)
  try {
    out = readParam(pnh, "out", out);
    options.rate_hz = readParam(pnh, "rate", options.rate_hz);
    options.duration_s = readParam(pnh, "duration", options.duration_s);
    options.warmup_s = readParam(pnh, "warmup", options.warmup_s);
    options.vibration_rate_hz = readParam(pnh, "vibration_rate", options.vibration_rate_hz);
    if (!(options.vibration_rate_hz >= 0.0 && options.vibration_rate_hz <= 1e6))
      throw InvalidInput("~vibration_rate: must be in [0, 1e6] Hz");
    if (!(options.rate_hz > 0.0 && options.rate_hz <= 1e5))
      throw InvalidInput("~rate: must be in (0, 1e5] Hz");
    if (!(options.duration_s > 0.0 && options.duration_s <= 86400.0))
      throw InvalidInput("~duration: must be in (0, 86400] s");
    if (!(options.warmup_s >= 0.0 && options.warmup_s < options.duration_s))
      throw InvalidInput("~warmup: must be in [0, ~duration) s");
  } catch (const InvalidInput& e) {
    ROS_FATAL("drivetrain_latency: %s", e.what());
    return 1;
  }

  LoadGenerator generator(nh, options);
  if (!generator.connect()) {
    ROS_FATAL("drivetrain_latency: no stiffness_estimator on %s, %s and /diagnostics after %g s",
              nh.resolveName("torque").c_str(), nh.resolveName("stiffness").c_str(),
              options.connect_timeout_s);
    return 1;
  }
  const LoadResult result = generator.run();
  nlohmann::json report = toJson(result);
  report["rate_hz"] = options.rate_hz;
  report["duration_s"] = options.duration_s;
  report["warmup_s"] = options.warmup_s;
  report["vibration_rate_hz"] = options.vibration_rate_hz;
  std::cout << report.dump(2) << std::endl;
  if (!out.empty() && !(std::ofstream(out) << report.dump(2) << "\n")) {
    ROS_FATAL("drivetrain_latency: ~out = '%s': cannot be written", out.c_str());
    return 1;
  }
  if (result.answered != result.sent) {
    ROS_WARN("drivetrain_latency: %llu of %llu inputs answered",
             static_cast<unsigned long long>(result.answered),
             static_cast<unsigned long long>(result.sent));
  }
  return 0;
}

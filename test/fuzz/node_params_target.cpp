// The node's private parameters on a hostile parameter file (drivetrain_replay --params reads the
// same YAML; the node reads the same names from the parameter server): readPipelineOptions and
// readOutputSettings, then the pipeline they configure, fed a few torque samples.
#include <yaml-cpp/yaml.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/config/yaml_parameters.hpp"
#include "drivetrain_stiffness/ros/node_parameters.hpp"
#include "field_rule.hpp"
#include "finite_checks.hpp"
#include "fuzz_target.hpp"
#include "pipeline_inputs.hpp"
#include "refusal.hpp"

namespace drivetrain_stiffness::fuzz {
namespace {

const RigConfig& seedServo() {
  static const RigConfig rig = loadRigFile(sourceDir() + "/config/gearboxes/seed_servo.yaml");
  return rig;
}

}  // namespace

CaseStats fuzzNodeParameters(const std::uint8_t* data, std::size_t size) {
  CaseStats stats;
  YAML::Node root;
  try {
    root = YAML::Load(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const YAML::Exception& e) {
    stats.refuse(std::string("not YAML (refused by the caller, as --params): ") + e.what());
    return stats;
  }
  if (!root.IsMap() && !root.IsNull()) {
    stats.refuse("not a map of parameters (refused by the caller, as --params)");
    return stats;
  }
  const YamlParameters get(root);  // drivetrain_replay --params reads the same way
  PipelineOptions options;
  RuntimeSettings runtime;
  OutputSettings settings;
  if (!acceptOrRefuse(
          stats, [&] { options = readPipelineOptions(get, seedServo()); },
          &requireNamesParameter) ||
      !acceptOrRefuse(
          stats, [&] { runtime = readRuntimeSettings(get, seedServo()); },
          &requireNamesParameter) ||
      !acceptOrRefuse(
          stats, [&] { settings = readOutputSettings(get); }, &requireNamesParameter) ||
      !acceptOrRefuse(
          stats, [&] { readJointNames(get); }, &requireNamesParameter)) {
    return stats;
  }
  // Accepted options must make a working pipeline (or be refused there, naming the parameter).
  acceptOrRefuse(
      stats,
      [&] {
        RigPipeline pipeline(seedServo(), options, runtime);
        FiniteSink sink;
        const std::int64_t epoch = 1767225600LL * 1000000000LL;
        for (int i = 0; i < 3; ++i) {
          feedTorque(pipeline, Stamp{epoch + i * 1000000LL}, 0.1, sink);
          // An encoder reading half-way: the measured-motion dynamics (~motion_slices,
          // ~mesh_phase_offset).
          MotionInput reading;
          reading.pinion_angle = 0.1 * i;
          reading.pinion_velocity = 100.0;
          feedMotion(pipeline, Stamp{epoch + i * 1000000LL + 500000LL}, reading, false, sink, {});
        }
        ++stats.accepted;
      },
      &requireNamesParameter);
  return stats;
}

}  // namespace drivetrain_stiffness::fuzz

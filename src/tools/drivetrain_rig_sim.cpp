// drivetrain_rig_sim: writes a bag of rig inputs for a documented scenario (rig_scenarios.hpp):
// /torque (geometry_msgs/WrenchStamped, torque.z [N*m]), /preload (drivetrain_stiffness/Preload)
// and /joint_states (sensor_msgs/JointState, the pinion and gear encoders) with header stamps and
// record times from a fixed epoch, so the bags are reproducible byte for byte (scenario_bag.hpp).
// Needs no master. Example:
//   drivetrain_rig_sim --scenario torque_ripple --config config/gearboxes/seed_servo.yaml --out ripple.bag
#include <CLI/CLI.hpp>
#include <iostream>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "rig_scenarios.hpp"  // NOLINT(build/include_subdir)
#include "scenario_bag.hpp"   // NOLINT(build/include_subdir)

int main(int argc, char** argv) {
  using namespace drivetrain_stiffness;
  CLI::App app{"Writes a bag of rig inputs (torque, preload, encoders) for a documented scenario"};
  ScenarioSpec spec;
  ScenarioBagOptions bag;
  std::string config, out;
  bool no_velocity = false;
  app.add_option("--scenario", spec.name, "Scenario:\n" + scenarioHelp())->required();
  app.add_option("--config", config, "Gearbox YAML (support names, configured preloads, dynamics block, teeth)")->required();
  app.add_option("--out", out, "Bag to write")->required();
  app.add_option("--duration", spec.duration, "[s] length of the scenario");
  app.add_option("--rate", spec.torque_rate, "[Hz] torque sample rate");
  app.add_option("--joint-rate", spec.joint_rate, "[Hz] encoder (joint_states) sample rate, 1000 by default; 0: none");
  app.add_flag("--no-velocity", no_velocity, "joint_states without velocity (the node differentiates the angle)");
  app.add_option("--epoch", bag.epoch, "[s] stamp of the scenario start");
  app.add_option("--torque-topic", bag.torque_topic);
  app.add_option("--preload-topic", bag.preload_topic);
  app.add_option("--joint-topic", bag.joint_topic, "sensor_msgs/JointState topic (/joint_states)");
  app.add_option("--pinion-joint", bag.pinion_joint, "JointState name of the pinion shaft (pinion)");
  app.add_option("--gear-joint", bag.gear_joint, "JointState name of the gear shaft (gear)");
  CLI11_PARSE(app, argc, argv);
  spec.joint_velocity = !no_velocity;
  try {
    const RigConfig rig = loadRigFile(config);
    const std::vector<RigEvent> events = makeScenario(rig, spec);
    const ScenarioBagCounts n = writeScenarioBag(events, bag, out);
    std::cout << "{\"scenario\": \"" << spec.name << "\", \"events\": " << events.size() << ", \"torque\": " << n.torque
              << ", \"preload\": " << n.preload << ", \"joint_states\": " << n.joint_states << ", \"bag\": \"" << out
              << "\"}\n";
  } catch (const std::exception& e) {
    std::cerr << "drivetrain_rig_sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

// drivetrain_rig_sim: writes a bag of rig inputs for a documented scenario (rig_scenarios.hpp):
// /torque (geometry_msgs/WrenchStamped, torque.z [N*m]), /preload (drivetrain_stiffness/Preload)
// and /joint_states (sensor_msgs/JointState, the pinion and gear encoders) with header stamps and
// record times from a fixed epoch, so the bags are reproducible byte for byte (scenario_bag.hpp).
// Needs no master. Example:
//   drivetrain_rig_sim --scenario torque_ripple --config config/gearboxes/seed_servo.yaml --out ripple.bag
// load_sweep (load_sweep.hpp) takes --seed and --speed-rpm and adds its truth to the summary:
//   drivetrain_rig_sim --scenario load_sweep --config test/data/perturbed_servo.yaml --out sweep.bag --seed 7
#include <CLI/CLI.hpp>
#include <cstdint>
#include <iostream>

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "load_sweep.hpp"     // NOLINT(build/include_subdir)
#include "rig_scenarios.hpp"  // NOLINT(build/include_subdir)
#include "scenario_bag.hpp"   // NOLINT(build/include_subdir)

namespace {

/// load_sweep's truth for the summary: what the calibration should find, and how the bag was made.
nlohmann::json truthJson(const drivetrain_stiffness::LoadSweep& sweep, const drivetrain_stiffness::LoadSweepSpec& spec) {
  using drivetrain_stiffness::kArcsecond;
  const drivetrain_stiffness::LoadSweepTruth& t = sweep.truth;
  nlohmann::json levels = nlohmann::json::array();
  for (const drivetrain_stiffness::LoadSweepLevel& l : t.levels) levels.push_back({{"t0", l.t0}, {"t1", l.t1}, {"torque", l.torque}});
  return {{"mesh_stiffness_scale", t.mesh_stiffness_scale},
          {"pinion_bearing_scale", t.bearing_scale[0]},
          {"gear_bearing_scale", t.bearing_scale[1]},
          {"preload_torque", t.preload_torque},
          {"knee_torque", t.knee_torque},
          {"reverse_knee_torque", t.reverse_knee_torque},
          {"seed", spec.seed},
          {"speed_rpm", spec.speed_rpm},
          {"joint_rate", spec.joint_rate},
          {"torque_rate", spec.torque_rate},
          {"duration", t.duration},
          {"gear_turn", t.gear_turn},
          {"eccentricity_arcsec", {t.eccentricity[0] / kArcsecond, t.eccentricity[1] / kArcsecond}},
          {"eccentricity_phase", {t.eccentricity_phase[0], t.eccentricity_phase[1]}},
          {"stamp_jitter", spec.stamp_jitter},
          {"torque_noise", spec.torque_noise},
          {"torque_noise_floor", spec.torque_noise_floor},
          {"levels", levels}};
}

}  // namespace

int main(int argc, char** argv) {
  using namespace drivetrain_stiffness;
  CLI::App app{"Writes a bag of rig inputs (torque, preload, encoders) for a documented scenario"};
  ScenarioSpec spec;
  ScenarioBagOptions bag;
  std::string config, out;
  bool no_velocity = false;
  drivetrain_stiffness::LoadSweepSpec sweep_spec;
  app.add_option("--scenario", spec.name, "Scenario:\n" + scenarioHelp())->required();
  app.add_option("--config", config, "Gearbox YAML (support names, configured preloads, dynamics block, teeth)")->required();
  app.add_option("--out", out, "Bag to write")->required();
  app.add_option("--duration", spec.duration, "[s] length of the scenario (2; load_sweep: its natural length, this scales its holds)");
  app.add_option("--rate", spec.torque_rate, "[Hz] torque sample rate");
  app.add_option("--joint-rate", spec.joint_rate, "[Hz] encoder (joint_states) sample rate, 1000 by default (load_sweep: 5000); 0: none");
  app.add_option("--seed", sweep_spec.seed, "load_sweep: seed of the encoder errors, stamp jitter and torque noise (1)");
  app.add_option("--speed-rpm", sweep_spec.speed_rpm, "load_sweep: [rpm] constant pinion speed (120)");
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
    const bool sweep = spec.name == "load_sweep";
    if (!sweep && (app.count("--seed") > 0 || app.count("--speed-rpm") > 0)) {
      throw InvalidInput("--seed and --speed-rpm: load_sweep only");
    }
    LoadSweep made;
    if (sweep) {
      sweep_spec.torque_rate = spec.torque_rate;
      if (app.count("--joint-rate") > 0) sweep_spec.joint_rate = spec.joint_rate;
      if (app.count("--duration") > 0) sweep_spec.duration = spec.duration;
      sweep_spec.joint_velocity = spec.joint_velocity;
      made = makeLoadSweep(rig, sweep_spec);
    } else {
      made.events = makeScenario(rig, spec);
    }
    const std::vector<RigEvent>& events = made.events;
    const ScenarioBagCounts n = writeScenarioBag(events, bag, out);
    std::cout << "{\"scenario\": \"" << spec.name << "\", \"events\": " << events.size() << ", \"torque\": " << n.torque
              << ", \"preload\": " << n.preload << ", \"joint_states\": " << n.joint_states << ", \"bag\": \"" << out << "\"";
    if (sweep) std::cout << ", \"truth\": " << truthJson(made, sweep_spec).dump();
    std::cout << "}\n";
  } catch (const std::exception& e) {
    std::cerr << "drivetrain_rig_sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

// drivetrain_rig_sim: writes a bag of rig inputs for a documented scenario (rig_scenarios.hpp):
// /torque (geometry_msgs/WrenchStamped, torque.z [N*m]), /preload (drivetrain_stiffness/Preload)
// and /joint_states (sensor_msgs/JointState, the pinion and gear encoders) with header stamps and
// record times from a fixed epoch, so the bags are reproducible byte for byte (scenario_bag.hpp).
// With --vibration-rate > 0 (51200 Hz by default) it adds /vibration (drivetrain_stiffness/
// VibrationBlock): the model's transverse accelerations at the two supports (rig_vibration.hpp).
// Needs no master. Example:
//   drivetrain_rig_sim --scenario torque_ripple --config config/gearboxes/seed_servo.yaml --out
//   ripple.bag
// load_sweep (load_sweep.hpp) takes --seed and --speed-rpm and adds its truth to the summary:
//   drivetrain_rig_sim --scenario load_sweep --config test/data/perturbed_servo.yaml --out
//   sweep.bag --seed 7
// --campaign DIR writes a test campaign instead of one bag (docs/campaign.md): --bags N bags of the
// scenario, bag i starting at --epoch + i * --interval with seed --seed + i, the rig's mesh
// stiffness scale (or its bearings', or its preload torque) multiplied by the --step-* factor from
// bag --step-at on, and DIR/truth.csv with each bag's true rig:
//   drivetrain_rig_sim --scenario load_sweep --config config/gearboxes/seed_servo.yaml --campaign
//   wear
//     --bags 8 --interval 3600 --step-at 4 --step-mesh-scale 0.9 --duration 12
#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include <nlohmann/json.hpp>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "scenarios/load_sweep.hpp"     // NOLINT(build/include_subdir)
#include "scenarios/rig_scenarios.hpp"  // NOLINT(build/include_subdir)
#include "rig_vibration.hpp"            // NOLINT(build/include_subdir)
#include "scenario_bag.hpp"             // NOLINT(build/include_subdir)

namespace {

/// load_sweep's truth for the summary: what the calibration should find, and how the bag was made.
nlohmann::json truthJson(const drivetrain_stiffness::LoadSweep& sweep,
                         const drivetrain_stiffness::LoadSweepSpec& spec) {
  using drivetrain_stiffness::kArcsecond;
  const drivetrain_stiffness::LoadSweepTruth& t = sweep.truth;
  nlohmann::json levels = nlohmann::json::array();
  for (const drivetrain_stiffness::LoadSweepLevel& l : t.levels)
    levels.push_back({{"t0", l.t0}, {"t1", l.t1}, {"torque", l.torque}});
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

/// The scenario's accelerometer record, or none for --vibration-rate 0.
std::optional<drivetrain_stiffness::VibrationRecord> simulateScenarioVibration(
    const drivetrain_stiffness::RigConfig& rig, const drivetrain_stiffness::ScenarioSpec& spec,
    const drivetrain_stiffness::LoadSweepSpec& sweep_spec,
    const drivetrain_stiffness::LoadSweep& made, const drivetrain_stiffness::VibrationSpec& v) {
  using namespace drivetrain_stiffness;
  if (v.rate == 0.0) return std::nullopt;
  if (spec.name == "load_sweep") {
    // The true torque steps between the holds (the published torque carries sensor noise).
    std::vector<TorqueKnot> knots;
    for (const LoadSweepLevel& l : made.truth.levels) {
      knots.push_back({l.t0, l.torque});
      knots.push_back({l.t1, l.torque});
    }
    return simulateVibration(rig, knots, SpeedProfile(sweep_spec.speed_rpm * kTwoPi / 60.0),
                             made.truth.duration, v);
  }
  return simulateVibration(rig, scenarioTorque(made.events), scenarioSpeedProfile(rig, spec),
                           spec.duration, v);
}

/// The --campaign options: how each bag's rig differs from --config's.
struct CampaignSpec {
  std::string dir;
  int bags = 0;
  double interval = 3600.0;      ///< [s] between bag starts
  int step_at = -1;              ///< first bag of the changed rig; < 0: no change
  double step_mesh_scale = 1.0;  ///< [-] multiplies mesh.stiffness_scale from step_at on
  double step_bearing_scale =
      1.0;  ///< [-] multiplies every bearing's stiffness_scale from step_at on
  double step_preload_scale = 1.0;  ///< [-] multiplies anti_backlash.preload_torque from step_at on
};

/// Bag `index` of the campaign: --config's rig with the step applied from step_at on.
drivetrain_stiffness::RigConfig campaignRig(drivetrain_stiffness::RigConfig rig,
                                            const CampaignSpec& c, int index) {
  if (c.step_at < 0 || index < c.step_at) return rig;
  rig.mesh_stiffness_scale *= c.step_mesh_scale;
  for (drivetrain_stiffness::BearingSupportConfig& b : rig.bearings)
    b.stiffness_scale *= c.step_bearing_scale;
  rig.anti_backlash.preload_torque *= c.step_preload_scale;
  return rig;
}

/// Writes the campaign's bags and DIR/truth.csv (one row per bag: file, start stamp [s], the true
/// scales and preload torque [N*m]); prints one JSON line per bag.
void writeCampaign(const drivetrain_stiffness::RigConfig& rig, const CampaignSpec& c,
                   const drivetrain_stiffness::ScenarioSpec& spec,
                   drivetrain_stiffness::LoadSweepSpec sweep_spec,
                   drivetrain_stiffness::ScenarioBagOptions bag,
                   drivetrain_stiffness::VibrationSpec vibration) {
  using namespace drivetrain_stiffness;
  if (c.bags < 1 || c.bags > 100000)
    throw InvalidInput("--bags: " + std::to_string(c.bags) + " (1 to 100000)");
  requirePositive("--interval", c.interval);
  for (const auto& [name, v] :
       {std::pair<const char*, double>{"--step-mesh-scale", c.step_mesh_scale},
        {"--step-bearing-scale", c.step_bearing_scale},
        {"--step-preload-scale", c.step_preload_scale}}) {
    requirePositive(name, v);
  }
  std::filesystem::create_directories(c.dir);
  std::ofstream truth(c.dir + "/truth.csv");
  truth
      << "bag,start,mesh_stiffness_scale,pinion_bearing_scale,gear_bearing_scale,preload_torque\n";
  truth.precision(17);
  const double epoch0 = bag.epoch;
  const std::uint64_t seed0 = sweep_spec.seed, vibration_seed0 = vibration.seed;
  for (int i = 0; i < c.bags; ++i) {
    const RigConfig bag_rig = campaignRig(rig, c, i);
    char name[32];
    std::snprintf(name, sizeof name, "bag_%03d.bag", i);
    bag.epoch = epoch0 + i * c.interval;
    sweep_spec.seed = seed0 + static_cast<std::uint64_t>(i);
    LoadSweep made;
    if (spec.name == "load_sweep") {
      made = makeLoadSweep(bag_rig, sweep_spec);
    } else {
      made.events = makeScenario(bag_rig, spec);
    }
    vibration.seed = vibration_seed0 + static_cast<std::uint64_t>(i);
    const std::optional<VibrationRecord> record =
        simulateScenarioVibration(bag_rig, spec, sweep_spec, made, vibration);
    writeScenarioBag(made.events, bag, c.dir + "/" + name, record ? &*record : nullptr);
    // The rig's own values (its supports' scales per shaft, as load_sweep's truth reports them).
    std::array<double, 2> bearing_scale{{1.0, 1.0}};
    for (const BearingSupportConfig& b : bag_rig.bearings)
      bearing_scale[static_cast<std::size_t>(b.shaft)] = b.stiffness_scale;
    truth << name << "," << bag.epoch << "," << bag_rig.mesh_stiffness_scale << ","
          << bearing_scale[0] << "," << bearing_scale[1] << ","
          << bag_rig.anti_backlash.preload_torque << "\n";
    std::cout << "{\"bag\": \"" << c.dir << "/" << name << "\", \"start\": " << std::fixed
              << bag.epoch << std::defaultfloat
              << ", \"mesh_stiffness_scale\": " << bag_rig.mesh_stiffness_scale << "}\n";
  }
}

/// The command line.
struct RigSimArgs {
  drivetrain_stiffness::ScenarioSpec spec;
  drivetrain_stiffness::ScenarioBagOptions bag;
  std::string config, out;
  bool no_velocity = false;
  drivetrain_stiffness::LoadSweepSpec sweep_spec;
  CampaignSpec campaign;
  drivetrain_stiffness::VibrationSpec vibration;
};

void addOptions(CLI::App& app, RigSimArgs& a) {
  using drivetrain_stiffness::scenarioHelp;
  app.add_option("--scenario", a.spec.name, "Scenario:\n" + scenarioHelp())->required();
  app.add_option("--config", a.config,
                 "Gearbox YAML (support names, configured preloads, dynamics block, teeth)")
      ->required();
  auto* out_opt = app.add_option("--out", a.out, "Bag to write");
  auto* campaign_opt = app.add_option("--campaign", a.campaign.dir,
                                      "Directory for a campaign of --bags bags (instead of --out)");
  out_opt->excludes(campaign_opt);
  app.add_option("--bags", a.campaign.bags, "--campaign: number of bags")->needs(campaign_opt);
  app.add_option("--interval", a.campaign.interval, "--campaign: [s] between bag starts (3600)")
      ->needs(campaign_opt);
  app.add_option("--step-at", a.campaign.step_at,
                 "--campaign: first bag (0-based) of the changed rig")
      ->needs(campaign_opt);
  app.add_option("--step-mesh-scale", a.campaign.step_mesh_scale,
                 "--campaign: factor on the mesh stiffness scale from --step-at on");
  app.add_option("--step-bearing-scale", a.campaign.step_bearing_scale,
                 "--campaign: factor on every bearing's stiffness scale from --step-at on");
  app.add_option("--step-preload-scale", a.campaign.step_preload_scale,
                 "--campaign: factor on the preload torque from --step-at on");
  app.add_option(
      "--duration", a.spec.duration,
      "[s] length of the scenario (2; load_sweep: its natural length, this scales its holds)");
  app.add_option("--rate", a.spec.torque_rate, "[Hz] torque sample rate");
  app.add_option(
      "--joint-rate", a.spec.joint_rate,
      "[Hz] encoder (joint_states) sample rate, 1000 by default (load_sweep: 5000); 0: none");
  app.add_option("--seed", a.sweep_spec.seed,
                 "load_sweep: seed of the encoder errors, stamp jitter and torque noise (1)");
  app.add_option("--speed-rpm", a.sweep_spec.speed_rpm,
                 "load_sweep: [rpm] constant pinion speed (120)");
  app.add_flag("--no-velocity", a.no_velocity,
               "joint_states without velocity (the node differentiates the angle)");
  app.add_option("--epoch", a.bag.epoch, "[s] stamp of the scenario start");
  app.add_option("--torque-topic", a.bag.torque_topic);
  app.add_option("--preload-topic", a.bag.preload_topic);
  app.add_option("--joint-topic", a.bag.joint_topic,
                 "sensor_msgs/JointState topic (/joint_states)");
  app.add_option("--pinion-joint", a.bag.pinion_joint,
                 "JointState name of the pinion shaft (pinion)");
  app.add_option("--gear-joint", a.bag.gear_joint, "JointState name of the gear shaft (gear)");
  app.add_option("--vibration-rate", a.vibration.rate,
                 "[Hz] accelerometer sample rate (51200); 0: no vibration topic");
  app.add_option("--vibration-block", a.vibration.block,
                 "samples per drivetrain_stiffness/VibrationBlock (1024)");
  app.add_option("--vibration-topic", a.bag.vibration_topic, "VibrationBlock topic (/vibration)");
  app.add_option("--vibration-roughness", a.vibration.roughness,
                 "[m] rms of the random mesh displacement (tooth roughness) per internal sample "
                 "(1e-7)");
  app.add_option("--vibration-seed", a.vibration.seed,
                 "seed of the roughness and the sensor noise (load_sweep's --seed, else 1); a "
                 "campaign's bag i adds i");
  app.add_option("--vibration-noise", a.vibration.noise,
                 "[m/s^2] rms of the accelerometers' white noise per sample (0.005)");
}

/// Writes the bag (or the campaign) the arguments ask for. Throws InvalidInput naming the option.
void runRigSim(const CLI::App& app, RigSimArgs& a) {
  using namespace drivetrain_stiffness;
  const RigConfig rig = loadRigFile(a.config);
  const bool sweep = a.spec.name == "load_sweep";
  if (!sweep && (app.count("--seed") > 0 || app.count("--speed-rpm") > 0)) {
    throw InvalidInput("--seed and --speed-rpm: load_sweep only");
  }
  // The vibration's seed: --vibration-seed, else load_sweep's --seed (1 by default).
  if (app.count("--vibration-seed") == 0) a.vibration.seed = a.sweep_spec.seed;
  requireNonNegative("--vibration-rate", a.vibration.rate);
  // The accelerations come from the dynamics block's model: without one, none unless asked for.
  if (!rig.dynamics.present && app.count("--vibration-rate") == 0) a.vibration.rate = 0.0;
  if (sweep) {
    a.sweep_spec.torque_rate = a.spec.torque_rate;
    if (app.count("--joint-rate") > 0) a.sweep_spec.joint_rate = a.spec.joint_rate;
    if (app.count("--duration") > 0) a.sweep_spec.duration = a.spec.duration;
    a.sweep_spec.joint_velocity = a.spec.joint_velocity;
  }
  if (!a.campaign.dir.empty()) {
    writeCampaign(rig, a.campaign, a.spec, a.sweep_spec, a.bag, a.vibration);
    return;
  }
  if (a.out.empty()) throw InvalidInput("--out or --campaign: one of them is required");
  LoadSweep made;
  if (sweep) {
    a.sweep_spec.torque_rate = a.spec.torque_rate;
    if (app.count("--joint-rate") > 0) a.sweep_spec.joint_rate = a.spec.joint_rate;
    if (app.count("--duration") > 0) a.sweep_spec.duration = a.spec.duration;
    a.sweep_spec.joint_velocity = a.spec.joint_velocity;
    made = makeLoadSweep(rig, a.sweep_spec);
  } else {
    made.events = makeScenario(rig, a.spec);
  }
  const std::vector<RigEvent>& events = made.events;
  const std::optional<VibrationRecord> record =
      simulateScenarioVibration(rig, a.spec, a.sweep_spec, made, a.vibration);
  const ScenarioBagCounts n = writeScenarioBag(events, a.bag, a.out, record ? &*record : nullptr);
  std::cout << "{\"scenario\": \"" << a.spec.name << "\", \"events\": " << events.size()
            << ", \"torque\": " << n.torque << ", \"preload\": " << n.preload
            << ", \"joint_states\": " << n.joint_states << ", \"bag\": \"" << a.out << "\"";
  if (record) std::cout << ", \"vibration\": " << n.vibration;
  if (sweep) std::cout << ", \"truth\": " << truthJson(made, a.sweep_spec).dump();
  std::cout << "}\n";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace drivetrain_stiffness;
  CLI::App app{"Writes a bag of rig inputs (torque, preload, encoders) for a documented scenario"};
  RigSimArgs a;
  addOptions(app, a);
  CLI11_PARSE(app, argc, argv);
  a.spec.joint_velocity = !a.no_velocity;
  try {
    runRigSim(app, a);
  } catch (const std::exception& e) {
    std::cerr << "drivetrain_rig_sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

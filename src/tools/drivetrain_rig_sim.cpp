// drivetrain_rig_sim: writes a bag of rig inputs for a documented scenario (rig_scenarios.hpp):
// /torque (geometry_msgs/WrenchStamped, torque.z [N*m]) and /preload (drivetrain_stiffness/Preload)
// with header stamps and record times from a fixed epoch, so the bags are reproducible byte for
// byte. Needs no master. Example:
//   drivetrain_rig_sim --scenario torque_ripple --config config/gearboxes/seed_servo.yaml --out ripple.bag
#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>

#include <geometry_msgs/WrenchStamped.h>
#include <rosbag/bag.h>

#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "rig_scenarios.hpp"  // NOLINT(build/include_subdir)

int main(int argc, char** argv) {
  using namespace drivetrain_stiffness;
  CLI::App app{"Writes a bag of rig inputs (torque, preload) for a documented scenario"};
  ScenarioSpec spec;
  std::string config, out, torque_topic = "/torque", preload_topic = "/preload";
  double epoch = 1767225600.0;  // 2026-01-01T00:00:00Z: a realistic epoch (1e9-second stamps)
  app.add_option("--scenario", spec.name, "Scenario:\n" + scenarioHelp())->required();
  app.add_option("--config", config, "Gearbox YAML (support names, configured preloads, dynamics block)")->required();
  app.add_option("--out", out, "Bag to write")->required();
  app.add_option("--duration", spec.duration, "[s] length of the scenario");
  app.add_option("--rate", spec.torque_rate, "[Hz] torque sample rate");
  app.add_option("--epoch", epoch, "[s] stamp of the scenario start");
  app.add_option("--torque-topic", torque_topic);
  app.add_option("--preload-topic", preload_topic);
  CLI11_PARSE(app, argc, argv);
  try {
    if (!(epoch >= 1.0 && epoch < 4e9)) throw InvalidInput("epoch = " + formatValue(epoch) + ": must be in [1, 4e9) s");
    const RigConfig rig = loadRigFile(config);
    const std::vector<RigEvent> events = makeScenario(rig, spec);
    const std::int64_t epoch_ns = std::llround(epoch * 1e9);
    rosbag::Bag bag(out, rosbag::bagmode::Write);
    // header.seq numbers each stream from 0, as rospy does; a gap is a message lost on the way.
    std::uint32_t seq = 0, preload_seq = 0;
    for (const RigEvent& e : events) {
      const std::int64_t ns = epoch_ns + std::llround(e.t * 1e9);  // record time: when the rig sent it
      const ros::Time record(static_cast<std::uint32_t>(ns / 1000000000LL), static_cast<std::uint32_t>(ns % 1000000000LL));
      const std::int64_t stamp_ns = ns + std::llround(e.stamp_offset * 1e9);
      const ros::Time stamp = e.zero_stamp ? ros::Time(0, 0)
                                           : ros::Time(static_cast<std::uint32_t>(stamp_ns / 1000000000LL),
                                                       static_cast<std::uint32_t>(stamp_ns % 1000000000LL));
      if (e.torque) {
        geometry_msgs::WrenchStamped w;
        seq += e.lost_before;
        w.header.seq = seq++;
        w.header.stamp = stamp;
        w.header.frame_id = e.frame_id;
        w.wrench.torque.z = *e.torque;
        bag.write(torque_topic, record, w);
      }
      if (!e.preload.empty()) {
        drivetrain_stiffness::Preload p;
        preload_seq += e.lost_before;
        p.header.seq = preload_seq++;
        p.header.stamp = stamp;
        for (const PreloadSetting& s : e.preload) {
          drivetrain_stiffness::BearingPreload b;
          b.name = s.name;
          b.axial_preload = s.axial_preload;
          b.radial_preload = s.radial_preload;
          b.inner_interference = s.inner_interference;
          b.outer_interference = s.outer_interference;
          p.bearings.push_back(b);
        }
        bag.write(preload_topic, record, p);
      }
    }
    bag.close();
    std::cout << "{\"scenario\": \"" << spec.name << "\", \"events\": " << events.size() << ", \"bag\": \"" << out << "\"}\n";
  } catch (const std::exception& e) {
    std::cerr << "drivetrain_rig_sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

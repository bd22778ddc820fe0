// RigPipeline's message inputs and run-time setters on hostile sequences (pipeline_decoder.hpp):
// nothing escapes but the documented refusals, every value refusal names its field, every input
// is counted, and every number handed to the sink is finite (FiniteSink).
#include <memory>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "field_rule.hpp"
#include "finite_checks.hpp"
#include "fuzz_target.hpp"
#include "pipeline_decoder.hpp"
#include "pipeline_inputs.hpp"
#include "refusal.hpp"

namespace drivetrain_stiffness::fuzz {
namespace {

const RigConfig& rigConfig(int index) {
  static const RigConfig rigs[] = {loadRigFile(sourceDir() + "/config/gearboxes/seed_servo.yaml"),
                                   loadRigFile(sourceDir() + "/test/data/ordinary_servo.yaml")};
  return rigs[index];
}

// What a value refusal of each input must name: the input's fields, or for a load no bearing
// equilibrium carries (UnreachableLoad), the support it concerns.
const std::vector<std::string> kTorqueFields = {"torque", "pinion_bearing", "gear_bearing"};
const std::vector<std::string> kMotionFields = {"pinion position", "pinion velocity",
                                                "gear position",   "~pinion_joint",
                                                "pinion_bearing",  "gear_bearing"};
const std::vector<std::string> kPreloadFields = {
    "name",           "axial_preload", "radial_preload", "inner_interference", "outer_interference",
    "pinion_bearing", "gear_bearing"};

// A value refusal's reason is counters().last_event after "<topic> rejected (<why>): ".
void checkOutcome(InputOutcome outcome, const RigPipeline& pipeline,
                  const std::vector<std::string>& fields, CaseStats& stats) {
  if (outcome == InputOutcome::kAccepted) {
    ++stats.accepted;
    return;
  }
  const std::string& event = pipeline.counters().last_event;
  stats.refuse(event);
  if (outcome != InputOutcome::kInvalidValue && outcome != InputOutcome::kUnreachableLoad)
    return;  // a stamp rule
  const auto colon = event.find("): ");
  if (colon == std::string::npos) throw FuzzFinding("refusal without a reason: \"" + event + "\"");
  requireNamesOneOf(event.substr(colon + 3), fields, "value refusal names no input field");
}

void checkCounts(const RigPipeline& pipeline, std::uint64_t torques, std::uint64_t preloads,
                 std::uint64_t motions) {
  const PipelineCounters& c = pipeline.counters();
  if (c.accepted_motion + c.rejected_motion != motions) {
    throw FuzzFinding("a joint_states message was not counted: " + std::to_string(motions) +
                      " sent, counters " + std::to_string(c.accepted_motion) + "+" +
                      std::to_string(c.rejected_motion));
  }
  if (c.accepted_torque + c.rejected_torque != torques ||
      c.accepted_preload + c.rejected_preload != preloads) {
    throw FuzzFinding("an input was not counted: " + std::to_string(torques) + " torques, " +
                      std::to_string(preloads) + " preloads, counters " +
                      std::to_string(c.accepted_torque) + "+" + std::to_string(c.rejected_torque) +
                      ", " + std::to_string(c.accepted_preload) + "+" +
                      std::to_string(c.rejected_preload));
  }
}

}  // namespace

CaseStats fuzzPipeline(const std::uint8_t* data, std::size_t size) {
  CaseStats stats;
  ByteReader in(data, size);
  const PipelineSetup setup = decodeSetup(in);
  std::unique_ptr<RigPipeline> pipeline;
  const bool built = acceptOrRefuse(
      stats,
      [&] {
        RuntimeSettings settings = RuntimeSettings::forRig(rigConfig(setup.rig));
        settings.fidelity = setup.settings.fidelity;
        settings.stiffness_rate = setup.settings.stiffness_rate;
        pipeline = std::make_unique<RigPipeline>(rigConfig(setup.rig), setup.options, settings);
      },
      &requireNamesParameter);
  if (!built) return stats;  // the decoder only picks valid options: the rule above says why not
  FiniteSink sink;
  Stamp now{0};
  std::uint64_t torques = 0, preloads = 0, motions = 0;
  std::uint32_t seq = 0, motion_seq = 0;
  const auto setter = [&](const std::vector<std::string>& fields, auto call) {
    if (acceptOrRefuse(stats, call, [&](const std::string& m) {
          requireNamesOneOf(m, fields, "setter refusal");
        })) {
      ++stats.accepted;
    }
  };
  for (int op = 0; op < kMaxOperations && !in.empty(); ++op) {
    const std::uint8_t op_byte = in.u8();
    if (op_byte >= 0xF0) {
      now = decodeStamp(in, now);
      const MotionCase m = decodeMotion(in);
      motion_seq = (m.numbering & 0x18) == 0x18
                       ? static_cast<std::uint32_t>(m.numbering >> 5)
                       : motion_seq + 1 + ((m.numbering & 0x18) == 0x10 ? m.numbering >> 5 : 0u);
      ++motions;
      acceptOrRefuse(
          stats,
          [&] {
            checkOutcome(feedMotion(*pipeline, now, m.reading, m.missing_pinion, sink,
                                    {"/encoders", motion_seq, ""}),
                         *pipeline, kMotionFields, stats);
          },
          [](const std::string& msg) {
            throw FuzzFinding("motion() threw instead of refusing: " + msg);
          });
      checkCounts(*pipeline, torques, preloads, motions);
      continue;
    }
    const int op_code = op_byte % 8;
    switch (op_code) {
      case 0:
      case 7: {
        const bool with_origin = op_code == 7;
        now = decodeStamp(in, now);
        const double torque = decodeValue(in, 0.3);
        // Opcode 7 also says where it came from: frame (the rig's, the gear's, none), numbering
        // (gaps, restarts, two publishers) and backlog (shed).
        InputOrigin origin;
        Backlog backlog = Backlog::kNone;
        if (with_origin) {
          const std::uint8_t meta = in.u8();
          static const char* kFrames[] = {"pinion", "pinion", "gear", ""};
          seq = (meta & 0x18) == 0x18 ? static_cast<std::uint32_t>(meta >> 5)
                                      : seq + 1 + ((meta & 0x18) == 0x10 ? meta >> 5 : 0u);
          origin = InputOrigin{(meta & 0x80) ? "/b" : "/a", seq, kFrames[meta & 3]};
          backlog = (meta & 4) ? Backlog::kShed : Backlog::kNone;
        }
        ++torques;
        acceptOrRefuse(
            stats,
            [&] {
              checkOutcome(feedTorque(*pipeline, now, torque, sink, origin, backlog), *pipeline,
                           kTorqueFields, stats);
            },
            [](const std::string& m) {
              throw FuzzFinding("torque() threw instead of refusing: " + m);
            });
        break;
      }
      case 1: {
        now = decodeStamp(in, now);
        const std::vector<PreloadSetting> settings = decodePreloads(in);
        ++preloads;
        acceptOrRefuse(
            stats,
            [&] {
              checkOutcome(feedPreload(*pipeline, now, settings, sink), *pipeline, kPreloadFields,
                           stats);
            },
            [](const std::string& m) {
              throw FuzzFinding("preload() threw instead of refusing: " + m);
            });
        break;
      }
      case 2: {
        now = decodeStamp(in, now);
        acceptOrRefuse(
            stats, [&] { pipeline->observeClock(now, sink); },
            [](const std::string& m) { throw FuzzFinding("observeClock() threw: " + m); });
        break;
      }
      case 3: {
        const double mesh = decodeValue(in, 0.1), bearing = decodeValue(in, 0.1);
        setter({"mesh_damping_ratio", "bearing_damping_ratio"}, [&] {
          RuntimeSettings s = pipeline->settings();
          s.mesh_damping_ratio = mesh;
          s.bearing_damping_ratio = bearing;
          pipeline->apply(s);
        });
        break;
      }
      case 4: {
        const Fidelity f = decodeFidelity(in.u8());
        setter({"fidelity"}, [&] {
          RuntimeSettings s = pipeline->settings();
          s.fidelity = f;
          pipeline->apply(s);
        });
        break;
      }
      case 5: {
        const double hz = decodeValue(in, 1000.0);
        setter({"stiffness_rate"}, [&] {
          RuntimeSettings s = pipeline->settings();
          s.stiffness_rate = hz;
          pipeline->apply(s);
        });
        break;
      }
      default: setter({}, [&] { pipeline->reset("fuzz"); }); break;
    }
    checkCounts(*pipeline, torques, preloads, motions);
  }
  return stats;
}

}  // namespace drivetrain_stiffness::fuzz

// RigPipeline's message inputs (torque, preload, encoders, accelerometer blocks) and run-time
// setters on hostile sequences (pipeline_decoder.hpp):
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
const std::vector<std::string> kVibrationFields = {"sample_rate", "channels", "data", "header.seq"};
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
                 std::uint64_t motions, std::uint64_t blocks) {
  const PipelineCounters& c = pipeline.counters();
  if (c.accepted_vibration + c.rejected_vibration != blocks) {
    throw FuzzFinding("a vibration block was not counted: " + std::to_string(blocks) +
                      " sent, counters " + std::to_string(c.accepted_vibration) + "+" +
                      std::to_string(c.rejected_vibration));
  }
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

/// One case's operations on a built pipeline, each checked and counted.
class PipelineCase {
 public:
  PipelineCase(ByteReader& in, RigPipeline& pipeline, CaseStats& stats)
      : in_(in), pipeline_(pipeline), stats_(stats) {}

  void run() {
    for (int op = 0; op < kMaxOperations && !in_.empty(); ++op) {
      const std::uint8_t op_byte = in_.u8();
      if (op_byte >= 0xF0) {
        motion();
      } else if (op_byte >= 0xE0) {
        vibration();
      } else {
        operation(op_byte % 8);
      }
      checkCounts(pipeline_, torques_, preloads_, motions_, blocks_);
    }
    // The end of the input (a replay's end of bag): an identification still pending is applied.
    acceptOrRefuse(
        stats_, [&] { pipeline_.finish(sink_); },
        [](const std::string& m) { throw FuzzFinding("finish() threw: " + m); });
  }

 private:
  template <typename Call>
  void setter(const std::vector<std::string>& fields, Call call) {
    if (acceptOrRefuse(stats_, call, [&](const std::string& m) {
          requireNamesOneOf(m, fields, "setter refusal");
        })) {
      ++stats_.accepted;
    }
  }

  void motion() {
    now_ = decodeStamp(in_, now_);
    const MotionCase m = decodeMotion(in_);
    motion_seq_ = (m.numbering & 0x18) == 0x18
                      ? static_cast<std::uint32_t>(m.numbering >> 5)
                      : motion_seq_ + 1 + ((m.numbering & 0x18) == 0x10 ? m.numbering >> 5 : 0u);
    ++motions_;
    acceptOrRefuse(
        stats_,
        [&] {
          checkOutcome(feedMotion(pipeline_, now_, m.reading, m.missing_pinion, sink_,
                                  {"/encoders", motion_seq_, ""}),
                       pipeline_, kMotionFields, stats_);
        },
        [](const std::string& msg) {
          throw FuzzFinding("motion() threw instead of refusing: " + msg);
        });
  }

  void vibration() {
    now_ = decodeStamp(in_, now_);
    const VibrationCase v = decodeVibration(in_);
    switch (v.numbering) {
      case 0: vibration_seq_ = 0; break;
      case 1: ++vibration_seq_; break;
      case 3: vibration_seq_ += 2; break;
      default: break;  // the same number again
    }
    VibrationBlockView block;
    block.sample_rate = v.sample_rate;
    block.channels = v.channels.data();
    block.channel_count = v.channels.size();
    block.data = v.data.data();
    block.size = v.data.size();
    ++blocks_;
    acceptOrRefuse(
        stats_,
        [&] {
          checkOutcome(
              feedVibration(pipeline_, now_, block, sink_, {"/vibration", vibration_seq_, ""}),
              pipeline_, kVibrationFields, stats_);
        },
        [](const std::string& m) {
          throw FuzzFinding("vibration() threw instead of refusing: " + m);
        });
  }

  void operation(int op_code) {
    switch (op_code) {
      case 0:
      case 7: torque(op_code == 7); break;
      case 1: preload(); break;
      case 2: {
        now_ = decodeStamp(in_, now_);
        acceptOrRefuse(
            stats_, [&] { pipeline_.observeClock(now_, sink_); },
            [](const std::string& m) { throw FuzzFinding("observeClock() threw: " + m); });
        break;
      }
      case 3: {
        const double mesh = decodeValue(in_, 0.1), bearing = decodeValue(in_, 0.1);
        setter({"mesh_damping_ratio", "bearing_damping_ratio"}, [&] {
          RuntimeSettings s = pipeline_.settings();
          s.mesh_damping_ratio = mesh;
          s.bearing_damping_ratio = bearing;
          pipeline_.apply(s);
        });
        break;
      }
      case 4: {
        const Fidelity f = decodeFidelity(in_.u8());
        setter({"fidelity"}, [&] {
          RuntimeSettings s = pipeline_.settings();
          s.fidelity = f;
          pipeline_.apply(s);
        });
        break;
      }
      case 5: {
        const double hz = decodeValue(in_, 1000.0);
        setter({"stiffness_rate"}, [&] {
          RuntimeSettings s = pipeline_.settings();
          s.stiffness_rate = hz;
          pipeline_.apply(s);
        });
        break;
      }
      default: setter({}, [&] { pipeline_.reset("fuzz"); }); break;
    }
  }

  void torque(bool with_origin) {
    now_ = decodeStamp(in_, now_);
    const double torque = decodeValue(in_, 0.3);
    // Opcode 7 also says where it came from: frame (the rig's, the gear's, none), numbering
    // (gaps, restarts, two publishers) and backlog (shed).
    InputOrigin origin;
    Backlog backlog = Backlog::kNone;
    if (with_origin) {
      const std::uint8_t meta = in_.u8();
      static const char* kFrames[] = {"pinion", "pinion", "gear", ""};
      seq_ = (meta & 0x18) == 0x18 ? static_cast<std::uint32_t>(meta >> 5)
                                   : seq_ + 1 + ((meta & 0x18) == 0x10 ? meta >> 5 : 0u);
      origin = InputOrigin{(meta & 0x80) ? "/b" : "/a", seq_, kFrames[meta & 3]};
      backlog = (meta & 4) ? Backlog::kShed : Backlog::kNone;
    }
    ++torques_;
    acceptOrRefuse(
        stats_,
        [&] {
          checkOutcome(feedTorque(pipeline_, now_, torque, sink_, origin, backlog), pipeline_,
                       kTorqueFields, stats_);
        },
        [](const std::string& m) {
          throw FuzzFinding("torque() threw instead of refusing: " + m);
        });
  }

  void preload() {
    now_ = decodeStamp(in_, now_);
    const std::vector<PreloadSetting> settings = decodePreloads(in_);
    ++preloads_;
    acceptOrRefuse(
        stats_,
        [&] {
          checkOutcome(feedPreload(pipeline_, now_, settings, sink_), pipeline_, kPreloadFields,
                       stats_);
        },
        [](const std::string& m) {
          throw FuzzFinding("preload() threw instead of refusing: " + m);
        });
  }

  ByteReader& in_;
  RigPipeline& pipeline_;
  CaseStats& stats_;
  FiniteSink sink_;
  Stamp now_{0};
  std::uint64_t torques_ = 0, preloads_ = 0, motions_ = 0, blocks_ = 0;
  std::uint32_t seq_ = 0, motion_seq_ = 0, vibration_seq_ = 0;
};

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
  PipelineCase(in, *pipeline, stats).run();
  stats.counters = namedCounters(pipeline->counters());
  return stats;
}

}  // namespace drivetrain_stiffness::fuzz

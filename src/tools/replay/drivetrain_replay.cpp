// drivetrain_replay: offline analysis of a recorded bag with the node's own pipeline (RigPipeline,
// the same class the stiffness_estimator node runs). Reads torque and preload with rosbag::View in
// record-time order, feeds them with their recorded stamps at full speed (no master, no /clock;
// the record time plays the role of the node's ROS clock for the clock-jump rule), and writes the
// node's output topics to a bag, CSV files and a short report with plots. Identical inputs give
// bit-identical outputs (nothing depends on the wall clock except the printed speed).
// A truncated or damaged bag is read up to the damage (ReplayInput): the outputs up to there are
// written and closed, the summary's status says "incomplete: ..." and the exit code is 4.
//   drivetrain_replay --bag rig.bag --config config/gearboxes/seed_servo.yaml --out out.bag
//   --report report/
#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <nlohmann/json.hpp>

#include <geometry_msgs/WrenchStamped.h>
#include <yaml-cpp/yaml.h>

#include "drivetrain_stiffness/Preload.h"
#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/core/dynamics/sliced_modal_propagator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/ros/node_parameters.hpp"
#include "common/python_script.hpp"  // NOLINT(build/include_subdir)
#include "bag/replay_input.hpp"      // NOLINT(build/include_subdir)
#include "drivetrain_stiffness/config/yaml_parameters.hpp"
#include "replay_summary.hpp"      // NOLINT(build/include_subdir)
#include "replay_writer.hpp"       // NOLINT(build/include_subdir)
#include "calibrated_gearbox.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

/// The node's parameter file (config/stiffness_estimator.yaml) read as the node would see it;
/// no file: every parameter at its default.
YamlParameters readParameterFile(const std::string& path) {
  if (path.empty()) return YamlParameters();
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw InvalidInput("--params = '" + path + "': " + e.what());
  }
  if (!root.IsMap() && !root.IsNull())
    throw InvalidInput("--params = '" + path + "': not a map of parameters");
  return YamlParameters(root);
}

// Exit codes (docs/replay_exit_codes.md); 2 is left unused (CLI11's own codes are mapped to 1).
constexpr int kExitOk = 0, kExitRefused = 1, kExitWrongType = 3, kExitIncomplete = 4,
              kExitNoTorque = 5;
constexpr char kExitCodesHelp[] =
    "Exit codes (docs/replay_exit_codes.md):\n"
    "  0  ok: the whole bag was read\n"
    "  1  refused or failed: bad options, an unreadable config or parameter file, a file that is "
    "not a\n"
    "     bag (nothing replayed); an output or the report that cannot be written; --calibrate "
    "without a\n"
    "     calibration, or after a bag in which no window updated it (the other outputs are "
    "written)\n"
    "  3  messages of the wrong type on the torque, preload or joint_states topic (counted as "
    "wrong_type;\n"
    "     stderr names the topic, the type found and the type expected)\n"
    "  4  incomplete: the bag is truncated or damaged; the outputs up to the damage are written "
    "and\n"
    "     closed, and the summary's status says \"incomplete: 'FILE' at byte OFFSET: ...\" (takes\n"
    "     precedence over 3 and 5)\n"
    "  5  no torque accepted: no message on the torque topic was accepted (none there, or every "
    "one\n"
    "     refused), so nothing was estimated; stderr's run summary says why, and lists the bag's "
    "topics\n"
    "     when a named one is absent";

/// The exit code's line in the run summary.
std::string exitMeaning(int code) {
  switch (code) {
    case kExitOk: return "ok";
    case kExitRefused: return "refused (--calibrate)";
    case kExitWrongType: return "messages of the wrong type";
    case kExitIncomplete: return "incomplete: the bag is damaged";
    case kExitNoTorque: return "no torque accepted";
  }
  return "?";
}

void ensureDirectory(const std::string& option, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw InvalidInput(option + " = '" + dir + "': not a directory and cannot be created");
}

/// Seconds since the epoch as UTC, ISO 8601 (for --calibrate's header comment).
std::string utc(std::time_t t) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

/// The live calibration's final state (the calibration rule), by the Calibration message's field
/// names.
nlohmann::json calibrationJson(const RigPipeline& pipeline) {
  nlohmann::json j;
  j["status"] = calibrationStatus(pipeline);
  const Calibrator* c = pipeline.calibrator();
  if (!c) return j;
  const CalibrationEstimate& e = c->estimate();
  for (int i = 0; i < kCalibrationSize; ++i) {
    j[calibrationName(i)] = e.value[i];
    j[std::string(calibrationName(i)) + "_std"] = e.std[i];
    j[std::string(calibrationName(i)) + "_identified"] =
        static_cast<bool>(e.identified[static_cast<std::size_t>(i)]);
  }
  // Why no window has updated the estimate yet, with the numbers (null once one has).
  const std::string waiting = c->waitingReason();
  j["waiting"] = waiting.empty() ? nlohmann::json(nullptr) : nlohmann::json(waiting);
  j["windows"] = e.windows;
  j["baseline_windows"] = e.baseline_windows;
  j["updates"] = e.updates;
  j["gated"] = e.gated;
  j["not_excited"] = e.not_excited;
  // Records of identified natural frequencies that updated the estimate or were gated, and the
  // last one's NIS (the Calibration message's modal_updates, modal_gated, modal_nis).
  j["modal_updates"] = e.modal_updates;
  j["modal_gated"] = e.modal_gated;
  j["modal_nis"] = e.modal_nis;
  // The model error the windows show per feature (mean TE, |C_1|, |C_2|), as a multiple of the
  // configured allowance; above 1 the std and bands above are widened (model_error_scale.hpp).
  j["model_error_scale"] = {e.model_error_scale[0], e.model_error_scale[1], e.model_error_scale[2]};
  return j;
}

nlohmann::json countersJson(const PipelineCounters& c) {
  nlohmann::json j;
  for (const auto& [key, count] : namedCounters(c)) j[key] = count;
  j["simulated_s"] = c.simulated_s;
  j["last_event"] = c.last_event;
  return j;
}

/// JSON text whatever bytes its strings hold (bag strings are escaped at the source; this also
/// covers a path or a config value given in another encoding).
std::string jsonText(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

/// Where the dynamics' time went, over the whole bag (the pipeline keeps its dynamics through
/// restarts): deterministic counts, unlike the speed. model_updates: the builds (at the start, and
/// at a restart after a change) and the bearing-stiffness or damping changes taken up while
/// running; dopri5_intervals: intervals handed to dopri5; the sliced propagation's (at the fidelity
/// of the bag's end: the full model's, or linear_modal's mean model's) slice crossings,
/// decompositions (general: by Eigen's eigensolver), contact changes located, and steps cut where
/// the regime bound could not clear them; at the nominal phase after a change, the stretches the
/// interval maps took and the intervals made (docs/model.md).
nlohmann::json dynamicsWorkJson(const DynamicsWork& w) {
  nlohmann::json work = {{"model_updates", w.rebuilds},
                         {"dopri5_intervals", w.fallback_intervals},
                         {"mapped_stretches", w.mapped_stretches},
                         {"interval_maps_made", w.interval_maps_made}};
  if (w.sliced) {
    work["slices_crossed"] = w.slices_crossed;
    work["slice_decompositions"] = w.decompositions;
    work["general_decompositions"] = w.general_decompositions;
    work["contact_changes"] = w.regime_changes;
    work["checked_substeps"] = w.checked_substeps;
  }
  return work;
}

/// The calibration's status, and while no window has updated it, why (Calibrator::waitingReason).
std::string calibrationLine(const nlohmann::json& calibration) {
  std::string line = calibration["status"].get<std::string>();
  if (calibration.contains("waiting") && calibration["waiting"].is_string())
    line += "; " + calibration["waiting"].get<std::string>();
  return line;
}

/// What the run did, for stderr: the status, the inputs, the calibration, the exit code's meaning.
std::string runSummaryText(const std::string& bag_path, std::uint64_t messages,
                           const nlohmann::json& summary, const ReplaySummary& inputs,
                           const RigPipeline& pipeline, const std::vector<BagTopic>& bag_topics,
                           int code) {
  std::string text = "drivetrain_replay: '" + printableText(bag_path) +
                     "': " + std::to_string(messages) + " messages read on the named topics, " +
                     std::to_string(ReplaySummary::accepted(pipeline.counters())) +
                     " inputs accepted\n";
  text += inputs.text(pipeline, bag_topics);
  text += "  calibration: " + calibrationLine(summary["calibration"]) + "\n";
  const std::string status = summary["status"].get<std::string>();
  if (status != "ok") text += "  status: " + status + "\n";
  text += inputs.wrongTypeText().empty() ? "" : "  wrong type: " + inputs.wrongTypeText();
  text += "  exit code " + std::to_string(code) + ": " + exitMeaning(code) + "\n";
  return text;
}

/// Writes `text` to `path`; throws InvalidInput naming `option` and the file if it cannot.
void writeTextFile(const std::string& option, const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << text;
  f.close();
  if (!f) throw InvalidInput(option + ": cannot write '" + path + "': " + std::strerror(errno));
}

/// report.md: the status and the run summary; plot_replay.py appends the figures when plots are on.
std::string reportMarkdown(const nlohmann::json& summary, const std::string& inputs_markdown,
                           const RigPipeline& pipeline, const std::string& out_bag) {
  std::ostringstream f;
  const std::string status = summary["status"].get<std::string>();
  f << "# Stiffness estimator report\n\n";
  if (status.rfind("incomplete", 0) == 0) {
    f << "**Incomplete replay**: the bag could not be read to its end; the outputs and the figures "
         "below cover the "
         "messages before the damage only.\n\n`"
      << status << "`\n\n";
  } else if (status != "ok") {
    f << "**No torque accepted**: no message on the torque topic was used, so there are no "
         "estimates; the inputs "
         "below say why.\n\n";
  }
  f << "Source: `" << summary["bag"].get<std::string>() << "`; outputs: `" << printableText(out_bag)
    << "`.\n\n";
  f << "## Inputs\n\n" << inputs_markdown << "\n";
  f << "## Calibration\n\n" << calibrationLine(summary["calibration"]) << "\n\n";
  const PipelineCounters& c = pipeline.counters();
  f << "## Outputs\n\n| output | count |\n|---|---|\n";
  for (const auto& [key, count] : namedCounters(c)) {
    if (key.size() > 10 && key.compare(key.size() - 10, 10, "_published") == 0)
      f << "| " << key << " | " << count << " |\n";
  }
  f << "| dynamics restarted after a gap / on an error | " << c.gap_restarts << " / "
    << c.dynamics_errors << " |\n";
  f << "| model time integrated | " << c.simulated_s << " s |\n";
  return f.str();
}

/// drivetrain_replay's command line.
struct ReplayOptions {
  std::string bag_path, config, params, out_bag, csv_dir, report_dir, calibrate_out;
  std::string torque_topic = "torque", preload_topic = "preload",
              joint_states_topic = "joint_states", vibration_topic = "vibration";
  /// Each stream's topic, indexed by InputStream.
  ReplayTopics topics() const {
    return {torque_topic, preload_topic, joint_states_topic, vibration_topic};
  }
  std::string plot_script = DRIVETRAIN_PLOT_REPLAY_SCRIPT;
  std::string compression = "lz4";
  std::string topics_option = "all", csv_topics_option;
  bool plots = true;
  bool modal_worker = false;
};

/// Parses the command line into `o`; returns an exit code when the run ends here (--help, bad
/// options).
std::optional<int> parseOptions(int argc, char** argv, ReplayOptions& o) {
  CLI::App app{
      "Replays a recorded bag through the stiffness estimator's pipeline (no master needed)"};
  app.footer(kExitCodesHelp);
  app.add_option("--bag", o.bag_path, "Recorded bag with the rig's torque and preload")->required();
  app.add_option("--config", o.config, "Gearbox YAML, as the node's ~gearbox_config")->required();
  app.add_option("--params", o.params,
                 "The node's parameter YAML (e.g. config/stiffness_estimator.yaml)");
  app.add_option("--out", o.out_bag, "Bag to write with the node's output topics");
  app.add_option("--compression", o.compression,
                 "Chunk compression of --out: lz4 (as rosbag record --lz4) or none")
      ->check(CLI::IsMember({"lz4", "none"}));
  app.add_option("--csv", o.csv_dir, "Directory for one CSV file per output topic");
  app.add_option("--topics", o.topics_option,
                 "Output topics written to --out and --csv (and the report's): all, or a "
                 "comma-separated list of "
                 "stiffness, transmission_error, te_spectrum, resonance, measured_te, calibration, "
                 "mesh_period_stats, "
                 "tf, rig_markers, modal_identification")
      ->capture_default_str();
  app.add_option("--csv-topics", o.csv_topics_option,
                 "Output topics written to --csv alone (default: --topics)");
  app.add_option("--calibrate", o.calibrate_out,
                 "Gearbox YAML to write with the calibrated values (needs a calibration: block in "
                 "--config and a window "
                 "that updated the calibration)");
  app.add_option("--report", o.report_dir,
                 "Directory for summary.json, report.md and PNG plots (CSV in DIR/csv, outputs in "
                 "DIR/outputs.bag unless "
                 "--csv, --out)");
  app.add_option("--torque-topic", o.torque_topic, "geometry_msgs/WrenchStamped, torque.z [N*m]");
  app.add_option("--preload-topic", o.preload_topic, "drivetrain_stiffness/Preload");
  app.add_option("--vibration-topic", o.vibration_topic,
                 "drivetrain_stiffness/VibrationBlock, the accelerometers (docs/vibration.md)");
  app.add_option(
      "--joint-states-topic", o.joint_states_topic,
      "sensor_msgs/JointState, the rig's encoders (~pinion_joint, ~gear_joint from --params)");
  app.add_option("--plot-script", o.plot_script,
                 "matplotlib script: OUTPUT_BAG REPORT_DIR INPUT_BAG");
  app.add_flag("!--no-plots", o.plots, "Write the report without PNG plots");
  app.add_flag("--modal-worker", o.modal_worker,
               "Identify the vibration records on a worker thread, as the node does (the same "
               "outputs, bit for bit)");
  try {
    app.parse(argc, argv);
  } catch (
      const CLI::ParseError& e) {  // --help is one too (exit code 0); CLI11's own codes are 100+
    return app.exit(e) == 0 ? kExitOk : kExitRefused;
  }
  return std::nullopt;
}

/// What the message loop read: the messages on the named topics and their first and last record
/// time.
struct ReadSpan {
  std::uint64_t messages = 0;
  std::optional<ros::Time> first, last;
  double seconds() const { return first ? (*last - *first).toSec() : 0.0; }
};

/// Feeds every message of `input` to the pipeline in record order, counting each on its topic.
ReadSpan replayMessages(ReplayInput& input, const ReplayOptions& o, const JointNames& joints,
                        RigPipeline& pipeline, ReplayWriter& writer, ReplaySummary& inputs) {
  ReadSpan span;
  std::string joint_refusal;
  std::vector<PreloadSetting> preload_settings;  // each preload message's, converted in place
  for (const ReplayMessage& m : input) {
    ++span.messages;
    if (!span.first) span.first = m.getTime();
    span.last = m.getTime();
    pipeline.observeClock(fromRosTime(m.getTime()), writer);
    // The recording publisher's caller id: its header.seq numbers what rosbag record received.
    const std::string& publisher = m.getCallerId();
    if (topicMatches(m.getTopic(), o.torque_topic)) {
      const auto w = m.instantiate<geometry_msgs::WrenchStamped>();
      inputs.read(InputStream::kTorque, w ? std::string() : m.getDataType());
      if (w) {
        const TorqueInput in = toTorqueInput(*w, publisher);
        pipeline.torque(in.stamp, in.torque, writer, in.origin);
      }
    } else if (topicMatches(m.getTopic(), o.joint_states_topic)) {
      const auto j = m.instantiate<sensor_msgs::JointState>();
      inputs.read(InputStream::kJointStates, j ? std::string() : m.getDataType());
      if (j) {
        const InputOrigin origin{publisher, j->header.seq, j->header.frame_id};
        const Stamp stamp = fromRosTime(j->header.stamp);
        const std::optional<MotionInput> reading = toMotionInput(*j, joints, joint_refusal);
        if (reading) {
          pipeline.motion(stamp, *reading, writer, origin);
        } else {
          pipeline.motionRefused(stamp, joint_refusal, origin, jointNamesOf(*j));
        }
      }
    } else if (topicMatches(m.getTopic(), o.vibration_topic)) {
      const auto v = m.instantiate<drivetrain_stiffness::VibrationBlock>();
      inputs.read(InputStream::kVibration, v ? std::string() : m.getDataType());
      if (v) {
        const VibrationBlockView block{v->sample_rate, v->channels.data(), v->channels.size(),
                                       v->data.data(), v->data.size()};
        pipeline.vibration(fromRosTime(v->header.stamp), block, writer,
                           {publisher, v->header.seq, v->header.frame_id});
      }
    } else {
      const auto p = m.instantiate<drivetrain_stiffness::Preload>();
      inputs.read(InputStream::kPreload, p ? std::string() : m.getDataType());
      if (p) {
        toPreloadSettings(*p, preload_settings);
        pipeline.preload(fromRosTime(p->header.stamp), preload_settings, writer,
                         {publisher, p->header.seq, p->header.frame_id});
      }
    }
  }
  return span;
}

/// summary.json (without `speed`): status, inputs, counters, calibration, final estimates.
nlohmann::json summaryJson(const ReplayOptions& o, const RigConfig& rig, const JointNames& joints,
                           const ReplayInput& input, const ReadSpan& span,
                           const ReplaySummary& inputs, const RigPipeline& pipeline,
                           const ReplayWriter& writer, const std::vector<BagTopic>& bag_topics) {
  nlohmann::json summary;
  summary["bag"] = printableText(o.bag_path);
  summary["status"] = "ok";
  if (const auto& damage = input.damage()) {
    summary["status"] = "incomplete: " + printableText(damage->describe(o.bag_path)) + "; " +
                        std::to_string(span.messages) + " messages read before it";
    summary["damage"] = {{"file", printableText(o.bag_path)},
                         {"offset", damage->offset},
                         {"what", printableText(damage->what)},
                         {"messages_before", span.messages}};
  } else if (pipeline.counters().accepted_torque == 0) {
    summary["status"] = "no torque accepted: no message on the torque topic '" +
                        printableText(o.torque_topic) + "' was accepted (" +
                        std::to_string(ReplaySummary::accepted(pipeline.counters())) +
                        " inputs accepted on the other topics); see \"inputs\"";
  }
  summary["messages"] = span.messages;
  summary["wrong_type"] = inputs.wrongType();
  summary["inputs"] = inputs.json(pipeline, bag_topics);
  summary["span_s"] = span.seconds();
  summary["topics"] = writer.topics().describe();         // what --out holds
  summary["csv_topics"] = writer.csvTopics().describe();  // what the CSV files hold
  // [s since the epoch] the first and last stamp read (null for a bag without one): a campaign
  // sorts by start.
  summary["start"] = span.first ? nlohmann::json(span.first->toSec()) : nlohmann::json(nullptr);
  summary["end"] = span.last ? nlohmann::json(span.last->toSec()) : nlohmann::json(nullptr);
  // What the report's motion figures read the input bag with (plot_replay.py): the encoders' topic
  // and joint names as this replay took them, and the tooth counts for the mesh orders.
  summary["encoders"] = {{"topic", o.joint_states_topic},
                         {"pinion_joint", joints.pinion},
                         {"gear_joint", joints.gear},
                         {"pinion_teeth", rig.gears.teeth[0]},
                         {"gear_teeth", rig.gears.teeth[1]}};
  const VibrationInput& vibration = pipeline.vibrationInput();
  std::vector<std::string> mapped;
  for (const VibrationChannel& c : vibration.channelMap()) mapped.push_back(printableText(c.name));
  summary["vibration"] = {{"topic", printableText(o.vibration_topic)},
                          {"channels", mapped},
                          {"unknown_channels", vibration.unknownNames()}};
  // At the last stamp read: the encoders' silence then (not reported here) is the bag's own.
  const PipelineDiagnostics diagnostics =
      pipeline.diagnostics(span.last ? fromRosTime(*span.last) : Stamp{});
  summary["counters"] = countersJson(diagnostics.counters);
  summary["calibration"] = calibrationJson(pipeline);
  // The per-mesh-period statistics over the bag (a campaign's row): speed, torque, TE RMS, force.
  summary["mesh_periods"] = writer.meshPeriodTotals().json();
  // The modal identifications over the bag (a campaign's row): per mode, the last identified.
  summary["modal"] = writer.modalTotals().json();
  if (diagnostics.dynamics) summary["dynamics_work"] = dynamicsWorkJson(diagnostics.dynamics->work);
  if (const auto& r = pipeline.lastResonance()) {
    for (const Mode& mode : r->modes)
      summary["final_resonance_hz"].push_back(mode.natural_frequency);
    summary["final_floquet_margin"] =
        r->floquet_valid ? nlohmann::json(r->floquet_margin) : nlohmann::json(nullptr);
  }
  for (const SupportEstimate& s : pipeline.estimator().current().supports) {
    summary["final_radial_stiffness"][s.name] = s.solution.radialStiffness();
  }
  return summary;
}

/// --calibrate: writes the calibrated gearbox, or says in `summary` why not; returns the refusal
/// ("" if written).
std::string writeCalibration(const ReplayOptions& o, const ReadSpan& span,
                             const RigPipeline& pipeline, nlohmann::json& summary) {
  CalibrationProvenance provenance;
  provenance.bag = std::filesystem::absolute(o.bag_path).string();
  if (span.first) {
    provenance.recorded = utc(static_cast<std::time_t>(span.first->sec)) + " to " +
                          utc(static_cast<std::time_t>(span.last->sec));
  }
  provenance.written = utc(std::time(nullptr));
  provenance.status = summary["status"].get<std::string>();
  try {
    writeCalibratedGearbox(o.config, pipeline.calibrator()->estimate(), o.calibrate_out,
                           provenance);
    summary["calibrated_gearbox"] = o.calibrate_out;
    return "";
  } catch (const std::exception& e) {
    summary["calibrated_gearbox"] = nullptr;
    summary["calibrate_error"] = e.what();
    return e.what();
  }
}

/// --topics, refused (InvalidInput) when a report's plots would miss their topics.
OutputTopics outputTopics(const ReplayOptions& o) {
  const OutputTopics topics = OutputTopics::parse("--topics", o.topics_option);
  const OutputTopics plotted =
      OutputTopics::parse("", "transmission_error,stiffness,resonance,mesh_period_stats");
  if (!o.report_dir.empty() && o.plots && !topics.includes(plotted)) {
    throw InvalidInput("--topics = '" + o.topics_option + "': the report's plots read " +
                       plotted.describe() + " from its outputs.bag; add them, or pass --no-plots");
  }
  return topics;
}

/// --report: summary.json, report.md and the plots; returns a failing plot script's refusal ("" if
/// none): every other output stays written.
std::string writeReport(const ReplayOptions& o, const nlohmann::json& summary,
                        const ReplaySummary& inputs, const RigPipeline& pipeline,
                        const std::vector<BagTopic>& bag_topics) {
  writeTextFile("--report", o.report_dir + "/summary.json", jsonText(summary) + "\n");
  writeTextFile(
      "--report", o.report_dir + "/report.md",
      reportMarkdown(summary, inputs.markdown(pipeline, bag_topics), pipeline, o.out_bag));
  if (o.plots) {
    try {
      runPythonScript("--plot-script", findScript(o.plot_script, "plot_replay.py"),
                      {o.out_bag, o.report_dir, o.bag_path, o.csv_dir});
    } catch (const InvalidInput& e) {
      return e.what();
    }
  }
  return "";
}

int run(int argc, char** argv) {
  ReplayOptions o;
  if (const std::optional<int> code = parseOptions(argc, argv, o)) return *code;

  // Refused before anything is read: one topic for two inputs, an unknown name, or a report whose
  // plots would miss their topics.
  ReplaySummary inputs(o.topics());
  inputs.requireDistinctTopics();
  const OutputTopics topics = outputTopics(o);
  const OutputTopics csv_topics = o.csv_topics_option.empty()
                                      ? topics
                                      : OutputTopics::parse("--csv-topics", o.csv_topics_option);
  const RigConfig rig = loadRigFile(o.config);
  const YamlParameters get = readParameterFile(o.params);
  PipelineOptions options = readPipelineOptions(get, rig);
  options.modal_worker = o.modal_worker;
  RigPipeline pipeline(rig, options, readRuntimeSettings(get, rig));
  if (!o.calibrate_out.empty() && !pipeline.calibrator()) {  // refused before anything is read
    throw InvalidInput("--calibrate = '" + o.calibrate_out +
                       "': no calibration runs with --config '" + o.config + "' (" +
                       calibrationStatus(pipeline) + ")");
  }
  if (!o.report_dir.empty()) {
    ensureDirectory("--report", o.report_dir);
    if (o.csv_dir.empty()) o.csv_dir = o.report_dir + "/csv";
    if (o.out_bag.empty())
      o.out_bag = o.report_dir + "/outputs.bag";  // what the report's plots read
  }
  if (!o.csv_dir.empty()) ensureDirectory("--csv", o.csv_dir);

  // Reads each message before the loop gets it: damage ends the input (input.damage()), it is
  // never thrown out of the loop, so the outputs below are always closed.
  ReplayInput input(o.bag_path, o.topics());
  const JointNames joints = readJointNames(get);
  ReplayWriter writer(pipeline, readOutputSettings(get), o.out_bag,
                      o.compression == "none" ? BagCompression::None : BagCompression::Lz4,
                      o.csv_dir, topics, csv_topics);
  const auto start = std::chrono::steady_clock::now();  // only for the printed speed
  const ReadSpan span = replayMessages(input, o, joints, pipeline, writer, inputs);
  pipeline.finish(writer);  // the last record's identification
  writer.close();
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const std::vector<BagTopic> bag_topics = input.topics();
  if (input.damage()) inputs.markDamaged();
  // The torque drives every estimate: without one accepted nothing was estimated or simulated.
  const bool no_torque = pipeline.counters().accepted_torque == 0;
  nlohmann::json summary =
      summaryJson(o, rig, joints, input, span, inputs, pipeline, writer, bag_topics);
  // --calibrate: written or refused (no window updated the calibration); the other outputs stand
  // either way.
  const std::string calibrate_error =
      o.calibrate_out.empty() ? "" : writeCalibration(o, span, pipeline, summary);
  std::string failure = calibrate_error;  // the refusal that makes the exit code 1
  if (!o.report_dir.empty()) {
    const std::string plot_failure = writeReport(o, summary, inputs, pipeline, bag_topics);
    if (failure.empty()) failure = plot_failure;
  }
  const int code = !failure.empty()         ? kExitRefused
                   : input.damage()         ? kExitIncomplete
                   : inputs.wrongType() > 0 ? kExitWrongType
                   : no_torque              ? kExitNoTorque
                                            : kExitOk;
  // Speed: separate from the outputs above, which must stay identical between runs. Without a
  // torque nothing was estimated or simulated: no speed to speak of.
  summary["speed"] = {
      {"wall_s", wall},
      {"realtime_factor", no_torque || !(wall > 0.0) ? nlohmann::json(nullptr)
                                                     : nlohmann::json(span.seconds() / wall)}};
  std::cout << jsonText(summary) << std::endl;
  // The run summary, on stderr at the end of every run (in report.md above).
  std::cerr << runSummaryText(o.bag_path, span.messages, summary, inputs, pipeline, bag_topics,
                              code);
  if (!failure.empty()) std::cerr << "drivetrain_replay: " << failure << "\n";
  return code;
}

}  // namespace
}  // namespace drivetrain_stiffness

int main(int argc, char** argv) {
  try {
    return drivetrain_stiffness::run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "drivetrain_replay: " << e.what() << "\n";
    return drivetrain_stiffness::kExitRefused;
  }
}

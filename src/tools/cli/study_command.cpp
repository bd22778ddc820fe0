// `drivetrain_cli study NAME --config FILE --out DIR`: one seed parameter study
// (parameter_studies.hpp) to DIR/NAME.csv and, unless --no-png, DIR/NAME.png
// (scripts/plot_study.py); a JSON summary with the first and last rows on stdout.
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/python_script.hpp"  // NOLINT(build/include_subdir): src/tools
#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/studies/parameter_studies.hpp"
#include "subcommand.hpp"

namespace drivetrain_stiffness::cli {
namespace {

struct StudyArgs {
  std::string name, config, out;
  std::string plot_script =
      DRIVETRAIN_PLOT_STUDY_SCRIPT;  ///< matplotlib script drawing the PNG from the CSV
  bool png = true;
};

int runStudyCommand(const StudyArgs& args) {
  const RigConfig rig = loadRigFile(args.config);
  const StudyTable table =
      drivetrain_stiffness::runStudy(args.name, rig);  // before touching the file system
  if (table.rows.empty()) throw InvalidInput("study '" + args.name + "' produced no rows");
  std::error_code ec;
  std::filesystem::create_directories(args.out, ec);
  if (ec || !std::filesystem::is_directory(args.out))
    throw InvalidInput("--out = '" + args.out + "': not a directory and cannot be created" +
                       (ec ? ": " + ec.message() : ""));
  const std::string csv = args.out + "/" + table.name + ".csv";
  writeStudyCsv(table, csv);
  nlohmann::json png = nullptr;
  if (args.png) {
    const std::string path = args.out + "/" + table.name + ".png";
    runPythonScript("--plot-script", findScript(args.plot_script, "plot_study.py"), {csv, path});
    png = path;
  }
  nlohmann::json first = nlohmann::json::object(), last = nlohmann::json::object();
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    first[table.columns[c]] = table.rows.front()[c];
    last[table.columns[c]] = table.rows.back()[c];
  }
  const nlohmann::json out = {{"study", table.name}, {"seed_figure", table.seed_figure},
                              {"kind", table.kind},  {"rows", table.rows.size()},
                              {"csv", csv},          {"png", png},
                              {"first_row", first},  {"last_row", last}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

}  // namespace

Subcommand addStudyCommand(CLI::App& app) {
  auto args = std::make_shared<StudyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "study", "a seed 000 parameter study (Figs 4, 5, 9, 10, 11) to CSV and PNG");
  cmd->add_option(
         "name", args->name,
         "bearing_shrink, bearing_preload, rms_sweep, resonance_shrink or resonance_preload")
      ->required()
      ->check(CLI::IsMember(studyNames()));
  cmd->add_option("--config", args->config, "gearbox YAML with gears, bearings and dynamics")
      ->required();
  cmd->add_option("--out", args->out, "output directory (created if missing)")->required();
  cmd->add_flag("!--no-png", args->png, "write the CSV only");
  cmd->add_option("--plot-script", args->plot_script, "matplotlib script: SCRIPT CSV PNG");
  return {cmd, [args] { return runStudyCommand(*args); }};
}

}  // namespace drivetrain_stiffness::cli

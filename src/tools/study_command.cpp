#include "study_command.hpp"

#include "python_script.hpp"  // NOLINT(build/include_subdir)

#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/studies/parameter_studies.hpp"

namespace drivetrain_stiffness {

int runStudyCommand(const StudyArgs& args) {
  const RigConfig rig = loadRigFile(args.config);
  const StudyTable table = runStudy(args.name, rig);  // before touching the file system
  if (table.rows.empty()) throw InvalidInput("study '" + args.name + "' produced no rows");
  std::error_code ec;
  std::filesystem::create_directories(args.out, ec);
  if (ec || !std::filesystem::is_directory(args.out))
    throw InvalidInput("--out = '" + args.out + "': not a directory and cannot be created" + (ec ? ": " + ec.message() : ""));
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
  const nlohmann::json out = {{"study", table.name}, {"seed_figure", table.seed_figure}, {"kind", table.kind},
                              {"rows", table.rows.size()}, {"csv", csv}, {"png", png},
                              {"first_row", first}, {"last_row", last}};
  std::cout << out.dump(2) << std::endl;
  return 0;
}

}  // namespace drivetrain_stiffness

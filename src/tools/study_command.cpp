#include "study_command.hpp"

#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/studies/parameter_studies.hpp"

extern char** environ;

namespace drivetrain_stiffness {
namespace {

/// Runs `python3 script csv png` without a shell (paths are passed verbatim, never interpreted).
/// Debian's /usr/bin/python3 first: a pyenv python earlier on PATH usually lacks matplotlib.
void plot(const std::string& script, const std::string& csv, const std::string& png) {
  const std::string python = ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> argv_s{python, script, csv, png};
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ);
  if (rc != 0) throw InvalidInput("--plot-script: cannot start python3: " + std::string(std::strerror(rc)));
  int status = 0;
  if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw InvalidInput("--plot-script = '" + script + "' failed for '" + csv + "' (the CSV is written; use --no-png to skip plots)");
}

}  // namespace

int runStudyCommand(const StudyArgs& args) {
  const RigConfig rig = loadRigFile(args.config);
  struct stat st {};
  if (::stat(args.out.c_str(), &st) != 0) {
    if (::mkdir(args.out.c_str(), 0755) != 0)
      throw InvalidInput("--out = '" + args.out + "': cannot create directory: " + std::strerror(errno));
  } else if (!S_ISDIR(st.st_mode)) {
    throw InvalidInput("--out = '" + args.out + "': exists and is not a directory");
  }
  const StudyTable table = runStudy(args.name, rig);
  const std::string csv = args.out + "/" + table.name + ".csv";
  writeStudyCsv(table, csv);
  nlohmann::json png = nullptr;
  if (args.png) {
    const std::string path = args.out + "/" + table.name + ".png";
    plot(args.plot_script, csv, path);
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

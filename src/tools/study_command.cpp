#include "study_command.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
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
/// Debian's /usr/bin/python3 first: a pyenv python earlier on PATH usually lacks matplotlib. The
/// script's stdout goes to our stderr, so it cannot corrupt the JSON on stdout.
void plot(const std::string& script, const std::string& csv, const std::string& png) {
  const std::string python = ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> argv_s{python, script, csv, png};
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, python.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw InvalidInput("--plot-script: cannot start " + python + ": " + std::strerror(rc));
  int status = 0;
  pid_t waited = 0;
  do {
    waited = waitpid(pid, &status, 0);
  } while (waited < 0 && errno == EINTR);
  if (waited < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw InvalidInput("--plot-script = '" + script + "' failed for '" + csv +
                       "' (the CSV is written; install python3-matplotlib or use --no-png)");
}

/// The compiled-in script (source tree), else the installed copy next to this executable.
std::string findPlotScript(const std::string& configured) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(configured, ec)) return configured;
  const fs::path beside = fs::read_symlink("/proc/self/exe", ec).parent_path() / "plot_study.py";
  if (!ec && fs::exists(beside, ec)) return beside.string();
  return configured;  // the error names the configured path
}

}  // namespace

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
    plot(findPlotScript(args.plot_script), csv, path);
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

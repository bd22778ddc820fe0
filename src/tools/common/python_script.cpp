#include "python_script.hpp"  // NOLINT(build/include_subdir)

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "drivetrain_stiffness/core/validation.hpp"

extern char** environ;

namespace drivetrain_stiffness {

void runPythonScript(const std::string& option, const std::string& script,
                     const std::vector<std::string>& args) {
  const std::string python =
      ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> argv_s{python, script};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, python.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw InvalidInput(option + ": cannot start " + python + ": " + std::strerror(rc));
  int status = 0;
  pid_t waited = 0;
  do {
    waited = waitpid(pid, &status, 0);
  } while (waited < 0 && errno == EINTR);
  if (waited < 0)
    throw InvalidInput(option + " = '" + script + "': cannot wait for it: " + std::strerror(errno));
  if (!WIFEXITED(status)) {
    throw InvalidInput(option + " = '" + script + "' ended by signal " +
                       std::to_string(WTERMSIG(status)) + " (the other outputs are written)");
  }
  if (WEXITSTATUS(status) != 0) {
    throw InvalidInput(option + " = '" + script + "' failed with exit code " +
                       std::to_string(WEXITSTATUS(status)) +
                       ": its message is above (the other outputs are written)");
  }
}

std::string findScript(const std::string& configured, const std::string& file_name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(configured, ec)) return configured;
  const fs::path beside = fs::read_symlink("/proc/self/exe", ec).parent_path() / file_name;
  if (!ec && fs::exists(beside, ec)) return beside.string();
  return configured;
}

}  // namespace drivetrain_stiffness

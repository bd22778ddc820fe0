#pragma once

#include <string>
#include <vector>

namespace drivetrain_stiffness {

/// Runs `python3 script args...` without a shell, /usr/bin/python3 first, its stdout to our stderr.
/// Throws InvalidInput naming `option` when it cannot run or fails.
void runPythonScript(const std::string& option, const std::string& script,
                     const std::vector<std::string>& args);

/// `configured` if it exists, else the installed `file_name` next to this executable, else
/// `configured`.
std::string findScript(const std::string& configured, const std::string& file_name);

}  // namespace drivetrain_stiffness

// Running the package's matplotlib scripts from the C++ tools (study plots, replay report).
#pragma once

#include <string>
#include <vector>

namespace drivetrain_stiffness {

/// Runs `python3 script args...` without a shell (arguments are passed verbatim, never
/// interpreted). Debian's /usr/bin/python3 first: a pyenv python earlier on PATH usually lacks
/// matplotlib. The script's stdout goes to our stderr, so it cannot corrupt JSON on stdout. Throws
/// InvalidInput naming `option` (the command-line option that chose the script) when it cannot run
/// or fails.
void runPythonScript(const std::string& option, const std::string& script,
                     const std::vector<std::string>& args);

/// The compiled-in script path (source tree) if it exists, else the installed copy named
/// `file_name` next to this executable, else `configured` (so the error names it).
std::string findScript(const std::string& configured, const std::string& file_name);

}  // namespace drivetrain_stiffness

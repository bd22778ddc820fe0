// `drivetrain_cli study NAME --config FILE --out DIR`: one seed parameter study to CSV and PNG.
#pragma once

#include <string>

namespace drivetrain_stiffness {

struct StudyArgs {
  std::string name, config, out;
  std::string plot_script;  ///< matplotlib script drawing the PNG from the CSV
  bool png = true;
};

/// Writes DIR/NAME.csv (and DIR/NAME.png unless !png), prints a JSON summary; returns the exit code.
int runStudyCommand(const StudyArgs& args);

}  // namespace drivetrain_stiffness

// Where the YAML targets put each case: the loaders take file paths (and a gearbox file names its
// bearing files relative to itself), so a case is written to a private temporary tree laid out
// like config/: gearboxes/ for gear and rig files, bearings/ for bearing files, with copies of
// config/bearings/*.yaml so that the seeds' `file: ../bearings/servo_7000ac.yaml` resolves.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace drivetrain_stiffness::fuzz {

class CaseFiles {
 public:
  /// The process's tree, created on first use and removed at exit.
  static CaseFiles& instance();
  ~CaseFiles();
  CaseFiles(const CaseFiles&) = delete;
  CaseFiles& operator=(const CaseFiles&) = delete;

  /// Writes the case to <root>/<subdir>/case.yaml (replacing the last one) and returns its path.
  std::string write(const std::string& subdir, const std::uint8_t* data, std::size_t size) const;
  const std::string& root() const { return root_; }

 private:
  CaseFiles();
  std::string root_;
};

}  // namespace drivetrain_stiffness::fuzz

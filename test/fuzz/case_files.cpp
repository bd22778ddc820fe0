#include "case_files.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "fuzz_target.hpp"

namespace drivetrain_stiffness::fuzz {
namespace fs = std::filesystem;

CaseFiles& CaseFiles::instance() {
  static CaseFiles files;
  return files;
}

CaseFiles::CaseFiles() {
  std::string pattern = (fs::temp_directory_path() / "drivetrain_fuzz.XXXXXX").string();
  if (!mkdtemp(pattern.data()))
    throw std::runtime_error("cannot create a temporary directory " + pattern);
  root_ = pattern;
  fs::create_directories(fs::path(root_) / "gearboxes");
  fs::create_directories(fs::path(root_) / "bearings");
  for (const auto& entry : fs::directory_iterator(fs::path(sourceDir()) / "config" / "bearings")) {
    fs::copy_file(entry.path(), fs::path(root_) / "bearings" / entry.path().filename());
  }
}

CaseFiles::~CaseFiles() {
  std::error_code ignored;  // nothing to do about a leftover temporary directory at exit
  fs::remove_all(root_, ignored);
}

std::string CaseFiles::write(const std::string& subdir, const std::uint8_t* data,
                             std::size_t size) const {
  const std::string path = root_ + "/" + subdir + "/case.yaml";
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out.flush()) throw std::runtime_error("cannot write " + path);
  return path;
}

}  // namespace drivetrain_stiffness::fuzz

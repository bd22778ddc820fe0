#include "calibrated_gearbox.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

namespace fs = std::filesystem;

/// The directory a relative `file:` of `path` resolves against (as loadRigFile's directoryOf).
fs::path directoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos
             ? fs::path(".")
             : fs::path(path.substr(0, slash).empty() ? "/" : path.substr(0, slash));
}

bool sameDirectory(const fs::path& a, const fs::path& b) {
  std::error_code ec1, ec2;
  const fs::path ca = fs::weakly_canonical(a, ec1), cb = fs::weakly_canonical(b, ec2);
  return !ec1 && !ec2 && ca == cb;
}

/// One line of free text in a comment.
std::string oneLine(std::string s) {
  for (char& c : s) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return s;
}

YAML::Node number(double value) { return YAML::Node(yamlNumber(value)); }

}  // namespace

std::string yamlNumber(double value) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  std::string s(buf, r.ptr);
  if (!std::isfinite(value))
    return s;  // never asked for: the estimate is finite (InvalidInput before)
  const auto e = s.find('e');
  std::string mantissa = s.substr(0, e), exponent = e == std::string::npos ? "" : s.substr(e + 1);
  if (mantissa.find('.') == std::string::npos) mantissa += ".0";
  if (!exponent.empty() && exponent[0] != '-' && exponent[0] != '+') exponent = "+" + exponent;
  return exponent.empty() ? mantissa : mantissa + "e" + exponent;
}

namespace {

/// Throws InvalidInput (naming --calibrate) for a rig without a calibration block, an estimate that
/// neither a window nor a record of natural frequencies updated, or a non-finite value or std.
void requireCalibrated(const std::string& config_path, const RigConfig& rig,
                       const CalibrationEstimate& estimate) {
  if (!rig.calibration.present) {
    throw InvalidInput("--calibrate: '" + config_path +
                       "' has no calibration: block: nothing was calibrated "
                       "(docs/calibration.md)");
  }
  if (estimate.updates == 0 && estimate.modal_updates == 0) {
    throw InvalidInput("--calibrate: no window of the bag updated the calibration (" +
                       std::to_string(estimate.windows) +
                       " windows: " + std::to_string(estimate.baseline_windows) + " baseline, " +
                       std::to_string(estimate.gated) + " gated, " +
                       std::to_string(estimate.not_excited) +
                       " not excited; last: " + toString(estimate.outcome) + "): nothing written");
  }
  for (int i = 0; i < kCalibrationSize; ++i) {
    requireFinite(std::string("--calibrate: ") + calibrationName(i), estimate.value[i]);
    requireFinite(std::string("--calibrate: ") + calibrationName(i) + "_std", estimate.std[i]);
  }
}

/// Sets the model's own values in `root`: the mesh, each bearing by its shaft, the scissor preload;
/// a relative bearing `file:` becomes absolute when out_path is in another directory.
void setModelValues(YAML::Node& root, const RigConfig& rig, const CalibrationEstimate& estimate,
                    const std::string& config_path, const std::string& out_path) {
  if (!root["mesh"] || !root["mesh"].IsMap()) root["mesh"] = YAML::Node(YAML::NodeType::Map);
  root["mesh"]["stiffness_scale"] = number(estimate.value[kMeshScale]);
  YAML::Node bearings = root["bearings"];
  const bool moved = !sameDirectory(directoryOf(config_path), directoryOf(out_path));
  for (std::size_t i = 0; i < bearings.size() && i < rig.bearings.size(); ++i) {
    YAML::Node entry = bearings[i];
    const int index = rig.bearings[i].shaft == 0 ? kPinionBearingScale : kGearBearingScale;
    entry["stiffness_scale"] = number(estimate.value[index]);
    if (entry["file"] && moved) {
      const std::string name = entry["file"].as<std::string>();
      if (!name.empty() && name[0] != '/') {
        std::error_code ec;
        const fs::path target = fs::weakly_canonical(directoryOf(config_path) / name, ec);
        entry["file"] = (ec ? fs::absolute(directoryOf(config_path) / name) : target).string();
      }
    }
  }
  if (rig.anti_backlash.spring_stiffness > 0.0 && root["anti_backlash"]) {
    root["anti_backlash"]["preload_torque"] = number(estimate.value[kPreloadTorque]);
  }
}

/// Sets root["calibration"] to the next run's priors.
///
/// The posterior becomes the next run's prior; the drawing's spread (this file's reference, its
/// std unless it was calibrated before) stays the one `identified` and the drift are judged
/// against. A parameter the data did not identify keeps the drawing's spread as its std: the file
/// holds no covariance, and the bearing scales' posterior stds (each about half the prior's, the
/// two strongly anti-correlated because only their compliances' sum is seen) would, as independent
/// priors, claim to know their difference, and the next run would flag them identified.
void setPriors(YAML::Node& root, const RigConfig& rig, const CalibrationEstimate& estimate) {
  YAML::Node calibration = root["calibration"];
  if (!calibration.IsMap())
    calibration = YAML::Node(YAML::NodeType::Map);  // `calibration: {}` or `calibration:`
  const CalibrationConfig& c = rig.calibration;
  const CalibrationPrior* drawing[kCalibrationSize] = {
      &c.mesh_stiffness_scale, &c.pinion_bearing_scale, &c.gear_bearing_scale, &c.preload_torque,
      &c.te_offset};
  for (int i = 0; i < kCalibrationSize; ++i) {
    YAML::Node prior(YAML::NodeType::Map);
    const bool held = !(estimate.prior_std[i] > 0.0);
    const bool identified = estimate.identified[static_cast<std::size_t>(i)];
    // The filter runs the bearing scales as compliances c = 1/s (calibrator.cpp), and converts a
    // spread at the file's mean, std(c) = std(s) / s^2: the drawing's spread, kept in compliance,
    // reads std(s) (s' / s)^2 at the calibrated mean s' (else a calibrated 0.7 would let the
    // bearings spread twice as far in compliance as the drawing did). At most the loader's range.
    double reference = drawing[i]->reference();
    if (i == kPinionBearingScale || i == kGearBearingScale) {
      const double ratio = estimate.value[i] / drawing[i]->mean;
      reference =
          std::min(reference * ratio * ratio, kScaleBound - kScaleLowest);  // the loader's widest
    }
    prior["mean"] = number(estimate.value[i]);
    prior["std"] = number(held ? 0.0 : identified ? estimate.std[i] : reference);
    prior["reference_std"] = number(reference);
    prior.SetStyle(YAML::EmitterStyle::Flow);
    calibration[calibrationName(i)] = prior;
  }
  calibration.SetStyle(YAML::EmitterStyle::Block);
  root["calibration"] = calibration;
}

/// The file's header comment: where the calibration came from, what it set, what it did not
/// identify.
std::string headerComment(const std::string& config_path, const RigConfig& rig,
                          const CalibrationEstimate& estimate,
                          const CalibrationProvenance& provenance) {
  std::string not_identified, held;
  for (int i = 0; i < kCalibrationSize; ++i) {
    if (estimate.identified[static_cast<std::size_t>(i)]) continue;
    std::string& list = estimate.prior_std[i] > 0.0 ? not_identified : held;
    list += (list.empty() ? "" : ", ") + std::string(calibrationName(i));
  }
  std::string header;
  header += "# Calibrated by drivetrain_replay --calibrate (docs/tools.md) from the gearbox file\n";
  header += "#   " + oneLine(fs::absolute(config_path).string()) + "\n";
  header += "# and the bag\n#   " + oneLine(provenance.bag) + "\n";
  if (!provenance.recorded.empty()) header += "# recorded " + oneLine(provenance.recorded) + "\n";
  if (!provenance.written.empty()) header += "# written " + oneLine(provenance.written) + "\n";
  if (!provenance.status.empty() && provenance.status != "ok")
    header += "# replay status: " + oneLine(provenance.status) + "\n";
  header += "# " + std::to_string(estimate.windows) +
            " windows: " + std::to_string(estimate.updates) + " updates, " +
            std::to_string(estimate.baseline_windows) + " baseline, " +
            std::to_string(estimate.gated) + " gated, " + std::to_string(estimate.not_excited) +
            " not excited.\n";
  header += "# Set from the posterior: mesh.stiffness_scale, bearings[].stiffness_scale (by shaft)";
  header += rig.anti_backlash.spring_stiffness > 0.0 ? ", anti_backlash.preload_torque" : "";
  header +=
      ", and calibration.<parameter>: {mean, std} (the next run's priors: the posterior std where\n"
      "# identified, the drawing's spread where not; reference_std: the drawing's spread, which\n"
      "# 'identified' and the drift are judged against).\n";
  header +=
      "# Not identified (posterior std not below half the drawing's spread; the value stays near "
      "its prior): " +
      (not_identified.empty() ? std::string("none") : not_identified) + "\n";
  if (!held.empty()) header += "# Held (prior std 0, not estimated): " + held + "\n";
  header += "# The original file's comments are not kept (re-written by yaml-cpp).\n";

  return header;
}

}  // namespace

std::string calibratedGearboxYaml(const std::string& config_path,
                                  const CalibrationEstimate& estimate, const std::string& out_path,
                                  const CalibrationProvenance& provenance) {
  // The config as the node reads it (the bearings' shafts, the scissor spring), then its YAML tree.
  const RigConfig rig = loadRigFile(config_path);
  requireCalibrated(config_path, rig, estimate);
  YAML::Node root = YAML::LoadFile(config_path);
  setModelValues(root, rig, estimate, config_path, out_path);
  setPriors(root, rig, estimate);
  const std::string header = headerComment(config_path, rig, estimate, provenance);

  YAML::Emitter out;
  out.SetIndent(2);
  out << root;
  if (!out.good())
    throw std::runtime_error("--calibrate: cannot emit the YAML: " + out.GetLastError());
  return header + out.c_str() + "\n";
}

void writeCalibratedGearbox(const std::string& config_path, const CalibrationEstimate& estimate,
                            const std::string& out_path, const CalibrationProvenance& provenance) {
  const std::string text = calibratedGearboxYaml(config_path, estimate, out_path, provenance);
  const fs::path parent = fs::path(out_path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
  }
  std::ofstream file(out_path, std::ios::binary | std::ios::trunc);
  if (!file)
    throw std::runtime_error("--calibrate = '" + out_path +
                             "': cannot write: " + std::strerror(errno));
  file << text;
  file.close();
  if (!file)
    throw std::runtime_error("--calibrate = '" + out_path +
                             "': cannot write: " + std::strerror(errno));
}

}  // namespace drivetrain_stiffness

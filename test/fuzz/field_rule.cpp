#include "field_rule.hpp"

#include <algorithm>
#include <cctype>

#include "fuzz_target.hpp"

namespace drivetrain_stiffness::fuzz {
namespace {

// The loaders' schema, written out here on purpose (not taken from yaml_config.cpp): a key the
// library starts to name in its messages must be a key a user can find in the documentation.
const std::vector<std::string>& schemaKeys() {
  static const std::vector<std::string> keys = {
      // blocks
      "bearing", "bearings", "gears", "anti_backlash", "mesh", "dynamics",
      // bearing:
      "type", "balls", "ball_diameter", "pitch_diameter", "inner_groove_conformity",
      "outer_groove_conformity", "diametral_clearance", "contact_angle_deg", "youngs_modulus",
      "poisson_ratio", "width", "ellipticity", "max_contact_pressure", "bore_diameter",
      "outside_diameter", "inner_raceway_diameter", "outer_raceway_diameter", "shaft_bore_diameter",
      "housing_outside_diameter", "shaft_youngs_modulus", "shaft_poisson_ratio",
      "housing_youngs_modulus", "housing_poisson_ratio", "inner_interference", "outer_interference",
      "arrangement", "tilt", "axial_preload", "radial_preload",
      // bearings[i] of a gearbox file
      "name", "shaft", "mesh_load_share", "file",
      // gears:
      "module", "pressure_angle_deg", "helix_angle_deg", "teeth", "profile_shift", "face_width",
      "center_distance", "addendum_coefficient", "tool_dedendum_coefficient",
      // anti_backlash:, mesh:
      "spring_stiffness", "preload_torque", "loaded_gear_face_width", "model", "samples",
      // dynamics:
      "pinion_mass", "gear_mass", "pinion_inertia", "gear_inertia", "mesh_damping_ratio",
      "bearing_damping_ratio", "bearing_clearance", "speed_rpm", "transmission_error_amplitude",
      "backlash", "torque",
      // calibration: (docs/calibration.md), its priors {mean, std, reference_std}
      "calibration", "mesh_stiffness_scale", "pinion_bearing_scale", "gear_bearing_scale",
      "te_offset", "baseline_torque", "torque_band", "min_speed_rpm", "max_mesh_to_natural", "gate",
      "model_error", "modal_model_error", "te_noise_floor", "drift", "reference_torque", "mean",
      "std", "reference_std"};
  return keys;
}

bool isIdentifierChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

bool isSchemaKey(const std::string& word) {
  const auto& keys = schemaKeys();
  return std::find(keys.begin(), keys.end(), word) != keys.end();
}

// The field assigned by the first "<field> = ": the identifier right before " = ", with a trailing
// [index] removed and only the last dotted segment kept ("bearings[0].name" -> "name").
std::string firstAssignedField(const std::string& text) {
  const auto eq = text.find(" = ");
  if (eq == std::string::npos) return {};
  std::size_t end = eq;
  while (end > 0 && text[end - 1] == ']') {
    const auto open = text.rfind('[', end - 1);
    if (open == std::string::npos) break;
    end = open;
  }
  std::size_t begin = end;
  while (begin > 0 && isIdentifierChar(text[begin - 1])) --begin;
  return text.substr(begin, end - begin);
}

[[noreturn]] void fail(const std::string& rule, const std::string& message) {
  throw FuzzFinding("refusal does not name its field (" + rule + "): \"" + message + "\"");
}

}  // namespace

bool containsWord(const std::string& text, const std::string& word) {
  for (auto pos = text.find(word); pos != std::string::npos; pos = text.find(word, pos + 1)) {
    const bool left = pos == 0 || !isIdentifierChar(text[pos - 1]);
    const bool right =
        pos + word.size() == text.size() || !isIdentifierChar(text[pos + word.size()]);
    if (left && right) return true;
  }
  return false;
}

void requireNamesYamlField(const std::string& message, const std::string& path) {
  if (message.rfind(path + ": ", 0) != 0)
    fail("does not begin with the file path " + path, message);
  const std::string rest = message.substr(path.size() + 2);
  if (rest.find("YAML syntax error at line ") != std::string::npos) return;
  // First: the quoted key of an unknown-key refusal is the document's, and may contain " = ".
  for (const std::string tail : {": unknown key", ": unknown top-level key"}) {
    if (rest.size() > tail.size() &&
        rest.compare(rest.size() - tail.size(), tail.size(), tail) == 0)
      return;
  }
  const std::string assigned = firstAssignedField(rest);
  if (!assigned.empty()) {
    if (!isSchemaKey(assigned))
      fail("assigns '" + assigned + "', not a key of the schema", message);
    return;
  }
  for (const std::string& key : schemaKeys()) {
    if (containsWord(rest, key)) return;
  }
  fail("names no key of the schema", message);
}

void requireNamesSchemaKey(const std::string& message) {
  requireNamesOneOf(message, schemaKeys(), "names no key of the schema");
}

const std::vector<std::string>& nodeParameterNames() {
  static const std::vector<std::string> names = {"max_abs_torque",
                                                 "max_preload",
                                                 "max_interference",
                                                 "bearing_load_tolerance",
                                                 "dynamics",
                                                 "fidelity",
                                                 "output_rate",
                                                 "max_gap",
                                                 "stamp_jump_back",
                                                 "clock_jump_back",
                                                 "resonance_threshold",
                                                 "spectrum_window",
                                                 "spectrum_hop",
                                                 "pinion_speed_rpm",
                                                 "stiffness_rate",
                                                 "rig_frame",
                                                 "pinion_frame",
                                                 "gear_frame",
                                                 "exaggeration",
                                                 "tf_rate",
                                                 "mesh_phase_offset",
                                                 "motion_timeout",
                                                 "gear_ratio_tolerance",
                                                 "motion_slices",
                                                 "pinion_joint",
                                                 "gear_joint",
                                                 "calibrate"};
  return names;
}

void requireNamesParameter(const std::string& message) {
  for (const std::string& name : nodeParameterNames()) {
    if (containsWord(message, name)) return;
  }
  fail("names no node parameter", message);
}

void requireNamesOneOf(const std::string& message, const std::vector<std::string>& fields,
                       const std::string& what) {
  for (const std::string& field : fields) {
    if (containsWord(message, field)) return;
  }
  fail(what, message);
}

}  // namespace drivetrain_stiffness::fuzz

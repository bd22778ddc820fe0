#include "drivetrain_stiffness/config/yaml_config.hpp"

#include <cmath>
#include <array>
#include <filesystem>
#include <ios>
#include <set>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
constexpr double kDegToRad = kPi / 180.0;

const std::set<std::string> kBearingKeys = {"type",
                                            "balls",
                                            "ball_diameter",
                                            "pitch_diameter",
                                            "inner_groove_conformity",
                                            "outer_groove_conformity",
                                            "diametral_clearance",
                                            "contact_angle_deg",
                                            "youngs_modulus",
                                            "poisson_ratio",
                                            "width",
                                            "ellipticity",
                                            "max_contact_pressure",
                                            "bore_diameter",
                                            "outside_diameter",
                                            "inner_raceway_diameter",
                                            "outer_raceway_diameter",
                                            "shaft_bore_diameter",
                                            "housing_outside_diameter",
                                            "shaft_youngs_modulus",
                                            "shaft_poisson_ratio",
                                            "housing_youngs_modulus",
                                            "housing_poisson_ratio",
                                            "inner_interference",
                                            "outer_interference",
                                            "arrangement",
                                            "tilt",
                                            "axial_preload",
                                            "radial_preload"};
const std::set<std::string> kRigBearingKeys = {"name", "shaft", "mesh_load_share", "file",
                                               "stiffness_scale"};

std::string key(const std::string& where, const std::string& name) { return where + "." + name; }

// A key from the file as it goes into a message: control characters escaped (\xNN), since what()
// is a C string and a NUL in a key would cut the message short before it names anything.
std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out.push_back(c);
    } else {
      static const char kHex[] = "0123456789abcdef";
      out += {'\\', 'x', kHex[u >> 4], kHex[u & 15]};
    }
  }
  return out;
}

// A mapping key as a name. YAML allows a sequence or a mapping as a key ("[a, b]: 1"), which
// as<std::string>() refuses with an untranslated YAML::TypedBadConversion; a null key ("~: 1") is
// returned as "~", which no schema contains (an unknown key).
std::string keyName(const YAML::Node& k, const std::string& where) {
  if (k.IsScalar()) return k.Scalar();
  if (k.IsNull()) return "~";
  throw InvalidInput(where + ": key '" + YAML::Dump(k) + "' is not a name");
}

void rejectUnknownKeys(const YAML::Node& node, const std::string& where,
                       const std::set<std::string>& a, const std::set<std::string>& b = {}) {
  for (const auto& item : node) {
    const std::string name = keyName(item.first, where);
    if (!a.count(name) && !b.count(name))
      throw InvalidInput(key(where, printable(name)) + ": unknown key");
  }
}

double readDouble(const YAML::Node& node, const std::string& where, const std::string& name) {
  const YAML::Node value = node[name];
  if (!value) throw InvalidInput(key(where, name) + ": required key is missing");
  try {
    return value.as<double>();
  } catch (const YAML::Exception&) {
    throw InvalidInput(key(where, name) + " = '" + YAML::Dump(value) + "': not a number");
  }
}

double readDouble(const YAML::Node& node, const std::string& where, const std::string& name,
                  double fallback) {
  return node[name] ? readDouble(node, where, name) : fallback;
}

int readInt(const YAML::Node& node, const std::string& where, const std::string& name) {
  const double v = readDouble(node, where, name);
  if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > 1e6)
    throwInvalid(key(where, name), v, "must be an integer");
  return static_cast<int>(v);
}

std::string readString(const YAML::Node& node, const std::string& where, const std::string& name,
                       const std::string& fallback) {
  if (!node[name]) return fallback;
  try {
    return node[name].as<std::string>();
  } catch (const YAML::Exception&) {
    throw InvalidInput(key(where, name) + ": must be a string");
  }
}

// Prefixes the field named in a core InvalidInput or UnreachableLoad (a preload the bearing cannot
// carry is refused at load time too) message with the YAML location.
template <typename F>
auto withContext(const std::string& where, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InvalidInput& e) {
    throw InvalidInput(where + ": " + e.what());
  } catch (const UnreachableLoad& e) {
    throw UnreachableLoad(where + ": " + e.what());
  }
}

YAML::Node loadFile(const std::string& path) {
  // Refused before yaml-cpp sees it: its reader throws std::ios_base::failure from the first read
  // of a directory, and leaks its 2 KB prefetch buffer doing so (LeakSanitizer, scripts/test
  // --sanitize).
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InvalidInput(path + ": is a directory, not a file");
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InvalidInput(path + ": cannot open file");
  } catch (const std::ios_base::failure& e) {  // opened but unreadable (EIO, ...)
    throw InvalidInput(path + ": cannot read file (" + e.what() + ")");
  } catch (const YAML::Exception& e) {
    throw InvalidInput(path + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                       ": " + e.msg);
  }
}

std::string directoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

}  // namespace

BearingSupportConfig parseBearing(const YAML::Node& node, const std::string& where) {
  if (!node || !node.IsMap()) throw InvalidInput(where + ": must be a mapping of bearing keys");
  rejectUnknownKeys(node, where, kBearingKeys, kRigBearingKeys);
  BearingSupportConfig cfg;
  BallBearingSpec& s = cfg.spec;
  s.type = parseBearingType(key(where, "type"), readString(node, where, "type", "angular_contact"));
  s.balls = readInt(node, where, "balls");
  s.ball_diameter = readDouble(node, where, "ball_diameter");
  s.pitch_diameter = readDouble(node, where, "pitch_diameter");
  s.inner_groove_conformity = readDouble(node, where, "inner_groove_conformity");
  s.outer_groove_conformity = readDouble(node, where, "outer_groove_conformity");
  if (node["diametral_clearance"] && node["contact_angle_deg"]) {
    throw InvalidInput(where + ": give diametral_clearance or contact_angle_deg, not both");
  }
  if (node["diametral_clearance"])
    s.diametral_clearance = readDouble(node, where, "diametral_clearance");
  else if (node["contact_angle_deg"]) {
    // Checked here in degrees: the bearing's own check names contact_angle in radians, which is not
    // what the file says.
    const double deg = readDouble(node, where, "contact_angle_deg");
    requireInHalfOpenRange(key(where, "contact_angle_deg"), deg, 0.0, 90.0);
    s.contact_angle = deg * kDegToRad;
  } else
    throw InvalidInput(where + ": one of diametral_clearance or contact_angle_deg is required");
  s.width = readDouble(node, where, "width", 0.0);
  s.material.youngs_modulus = readDouble(node, where, "youngs_modulus");
  s.material.poisson_ratio = readDouble(node, where, "poisson_ratio");
  s.ellipticity = parseEllipticityMethod(key(where, "ellipticity"),
                                         readString(node, where, "ellipticity", "exact"));
  s.max_contact_pressure = readDouble(node, where, "max_contact_pressure", s.max_contact_pressure);

  if (node["bore_diameter"] || node["outside_diameter"]) {
    FitGeometry g;
    g.bore_diameter = readDouble(node, where, "bore_diameter");
    g.outside_diameter = readDouble(node, where, "outside_diameter");
    // Groove-bottom diameters default to d_m -/+ D (zero-clearance groove bottoms).
    g.inner_raceway_diameter =
        readDouble(node, where, "inner_raceway_diameter", s.pitch_diameter - s.ball_diameter);
    g.outer_raceway_diameter =
        readDouble(node, where, "outer_raceway_diameter", s.pitch_diameter + s.ball_diameter);
    g.shaft_bore_diameter = readDouble(node, where, "shaft_bore_diameter", 0.0);
    g.housing_outside_diameter = readDouble(node, where, "housing_outside_diameter", INFINITY);
    g.shaft = {readDouble(node, where, "shaft_youngs_modulus", s.material.youngs_modulus),
               readDouble(node, where, "shaft_poisson_ratio", s.material.poisson_ratio)};
    g.housing = {readDouble(node, where, "housing_youngs_modulus", s.material.youngs_modulus),
                 readDouble(node, where, "housing_poisson_ratio", s.material.poisson_ratio)};
    s.fit = g;
  }
  cfg.arrangement =
      parseArrangement(key(where, "arrangement"), readString(node, where, "arrangement", "single"));
  cfg.tilt = parseTiltCondition(key(where, "tilt"), readString(node, where, "tilt", "constrained"));
  cfg.axial_preload = readDouble(node, where, "axial_preload", 0.0);
  cfg.radial_preload = readDouble(node, where, "radial_preload", 0.0);
  cfg.interference.inner = readDouble(node, where, "inner_interference", 0.0);
  cfg.interference.outer = readDouble(node, where, "outer_interference", 0.0);
  requireNonNegative(key(where, "radial_preload"), cfg.radial_preload);
  // Build once so that every geometric and preload check runs at load time.
  withContext(where, [&] {
    return BearingSupport(cfg.spec, cfg.arrangement, cfg.axial_preload, cfg.interference, cfg.tilt);
  });
  return cfg;
}

namespace {
const std::set<std::string> kGearKeys = {
    "module",          "pressure_angle_deg",   "helix_angle_deg",
    "teeth",           "profile_shift",        "face_width",
    "center_distance", "addendum_coefficient", "tool_dedendum_coefficient",
    "youngs_modulus",  "poisson_ratio",        "bore_diameter"};
const std::set<std::string> kAntiBacklashKeys = {"spring_stiffness", "preload_torque",
                                                 "loaded_gear_face_width"};
const std::set<std::string> kMeshKeys = {"model", "samples", "stiffness_scale"};
const std::set<std::string> kDynamicsKeys = {"pinion_mass",
                                             "gear_mass",
                                             "pinion_inertia",
                                             "gear_inertia",
                                             "mesh_damping_ratio",
                                             "bearing_damping_ratio",
                                             "bearing_clearance",
                                             "speed_rpm",
                                             "transmission_error_amplitude",
                                             "backlash",
                                             "torque"};

std::array<double, 2> readPair(const YAML::Node& node, const std::string& where,
                               const std::string& name, std::array<double, 2> fallback) {
  const YAML::Node v = node[name];
  if (!v) return fallback;
  if (!v.IsSequence() || v.size() != 2)
    throw InvalidInput(key(where, name) + ": must be [pinion, gear]");
  std::array<double, 2> out{};
  for (int i = 0; i < 2; ++i) {
    try {
      out[i] = v[i].as<double>();
    } catch (const YAML::Exception&) {
      throw InvalidInput(key(where, name) + "[" + std::to_string(i) + "] = '" + YAML::Dump(v[i]) +
                         "': not a number");
    }
  }
  return out;
}
}  // namespace

void parseGears(const YAML::Node& root, const std::string& file, RigConfig& rig) {
  const std::string where = file + ": gears";
  const YAML::Node gears = root["gears"];
  if (!gears || !gears.IsMap()) throw InvalidInput(file + ": needs a 'gears:' mapping");
  rejectUnknownKeys(gears, where, kGearKeys);
  GearPairSpec& g = rig.gears;
  g.module = readDouble(gears, where, "module");
  g.pressure_angle = readDouble(gears, where, "pressure_angle_deg") * kDegToRad;
  g.helix_angle = readDouble(gears, where, "helix_angle_deg", 0.0) * kDegToRad;
  if (!gears["teeth"]) throw InvalidInput(where + ".teeth: required key is missing");
  const std::array<double, 2> teeth = readPair(gears, where, "teeth", {0.0, 0.0});
  for (int i = 0; i < 2; ++i) {
    if (teeth[i] != std::floor(teeth[i]) || std::abs(teeth[i]) > 1e6) {
      throwInvalid(where + ".teeth[" + std::to_string(i) + "]", teeth[i], "must be an integer");
    }
    g.teeth[i] = static_cast<int>(teeth[i]);
  }
  g.profile_shift = readPair(gears, where, "profile_shift", {0.0, 0.0});
  g.face_width = readDouble(gears, where, "face_width", 0.0);
  if (gears["center_distance"]) g.center_distance = readDouble(gears, where, "center_distance");
  g.addendum_coefficient = readDouble(gears, where, "addendum_coefficient", g.addendum_coefficient);
  g.tool_dedendum_coefficient =
      readDouble(gears, where, "tool_dedendum_coefficient", g.tool_dedendum_coefficient);
  g.material.youngs_modulus = readDouble(gears, where, "youngs_modulus", g.material.youngs_modulus);
  g.material.poisson_ratio = readDouble(gears, where, "poisson_ratio", g.material.poisson_ratio);
  g.bore_diameter = readPair(gears, where, "bore_diameter", {0.0, 0.0});
  withContext(file, [&] { return SpurGearGeometry(g); });  // every geometric check at load time

  if (const YAML::Node ab = root["anti_backlash"]) {
    const std::string w = file + ": anti_backlash";
    if (!ab.IsMap()) throw InvalidInput(w + ": must be a mapping");
    rejectUnknownKeys(ab, w, kAntiBacklashKeys);
    rig.anti_backlash.spring_stiffness = readDouble(ab, w, "spring_stiffness");
    rig.anti_backlash.preload_torque = readDouble(ab, w, "preload_torque");
    rig.anti_backlash.loaded_gear_face_width = readDouble(ab, w, "loaded_gear_face_width", 0.0);
    withContext(file, [&] {
      requirePositive("anti_backlash.spring_stiffness",
                      rig.anti_backlash.spring_stiffness);  // the block means a spring
      validateAntiBacklash(rig.anti_backlash);
    });
  }
  if (const YAML::Node mesh = root["mesh"]) {
    if (!mesh.IsMap()) throw InvalidInput(file + ": mesh: must be a mapping");
    rejectUnknownKeys(mesh, file + ": mesh", kMeshKeys);
    const std::string w = file + ": mesh";
    rig.mesh_model =
        parseMeshStiffnessModel(key(w, "model"), readString(mesh, w, "model", "potential_energy"));
    if (mesh["samples"]) rig.mesh_samples = readInt(mesh, w, "samples");
    if (rig.mesh_samples < 16 || rig.mesh_samples > 100000)
      throwInvalid(key(w, "samples"), rig.mesh_samples, "must be in [16, 100000]");
    rig.mesh_stiffness_scale = readDouble(mesh, w, "stiffness_scale", 1.0);
    requireInHalfOpenRange(key(w, "stiffness_scale"), rig.mesh_stiffness_scale, kScaleLowest,
                           kScaleBound);
  }
}

// The dynamics block's value checks (the caller adds the file to the field named).
static void checkDynamics(const DynamicsConfig& c) {
  requirePositive("dynamics.pinion_mass", c.pinion_mass);
  requirePositive("dynamics.gear_mass", c.gear_mass);
  requirePositive("dynamics.pinion_inertia", c.pinion_inertia);
  requirePositive("dynamics.gear_inertia", c.gear_inertia);
  requireDampingRatio("dynamics.mesh_damping_ratio", c.mesh_damping_ratio);
  requireDampingRatio("dynamics.bearing_damping_ratio", c.bearing_damping_ratio);
  for (int i = 0; i < 2; ++i)
    requireNonNegative("dynamics.bearing_clearance[" + std::to_string(i) + "]",
                       c.bearing_clearance[i]);
  requirePositive("dynamics.speed_rpm", c.speed_rpm);
  requireNonNegative("dynamics.transmission_error_amplitude", c.transmission_error_amplitude);
  requireNonNegative("dynamics.backlash", c.backlash);
  requireFinite("dynamics.torque", c.torque);
}

const std::set<std::string> kCalibrationKeys = {"mesh_stiffness_scale",
                                                "pinion_bearing_scale",
                                                "gear_bearing_scale",
                                                "preload_torque",
                                                "te_offset",
                                                "baseline_torque",
                                                "torque_band",
                                                "min_speed_rpm",
                                                "max_mesh_to_natural",
                                                "gate",
                                                "model_error",
                                                "modal_model_error",
                                                "te_noise_floor",
                                                "drift",
                                                "reference_torque"};

// A prior `{mean: M, std: S}`; the mean defaults to `fallback` (the rig's own value).
static CalibrationPrior readPrior(const YAML::Node& c, const std::string& w,
                                  const std::string& name, CalibrationPrior prior, double lower,
                                  double upper) {
  if (c[name]) {
    const YAML::Node p = c[name];
    const std::string where = key(w, name);
    if (!p.IsMap()) throw InvalidInput(where + ": must be a mapping {mean: ..., std: ...}");
    rejectUnknownKeys(p, where, {"mean", "std", "reference_std"});
    prior.mean = readDouble(p, where, "mean", prior.mean);
    prior.std = readDouble(p, where, "std", prior.std);
    if (p["reference_std"]) {
      prior.reference_std = readDouble(p, where, "reference_std", prior.std);
      requireNonNegative(where + ".reference_std", prior.reference_std);
      requireAtMost(where + ".reference_std", prior.reference_std, upper - lower);
    }
  }
  requireInHalfOpenRange(key(w, name) + ".mean", prior.mean, lower, upper);
  requireNonNegative(key(w, name) + ".std", prior.std);
  requireAtMost(key(w, name) + ".std", prior.std, upper - lower);
  if (prior.std > 0.0 && prior.reference_std == 0.0) {
    // Estimated, but judged against no spread: never identified, never drifting.
    throwInvalid(
        key(w, name) + ".reference_std", prior.reference_std,
        "must be positive for an estimated parameter (std > 0); leave it out to judge against std");
  }
  return prior;
}

// The optional top-level block `name` of `file`, checked to be a mapping of known keys; a null
// node when the file has none.
static YAML::Node optionalBlock(const YAML::Node& root, const std::string& file,
                                const std::string& name, const std::set<std::string>& keys) {
  const YAML::Node block = root[name];
  if (!block) return block;
  const std::string w = file + ": " + name;
  if (!block.IsMap()) throw InvalidInput(w + ": must be a mapping");
  rejectUnknownKeys(block, w, keys);
  return block;
}

// The calibration block (docs/calibration.md); its prior means default to the rig's own values.
static void parseCalibration(const YAML::Node& root, const std::string& file, RigConfig& rig) {
  const YAML::Node c = optionalBlock(root, file, "calibration", kCalibrationKeys);
  if (!c) return;
  const std::string w = file + ": calibration";
  CalibrationConfig& k = rig.calibration;
  k.present = true;
  auto shaftScale = [&](int shaft) {
    for (const BearingSupportConfig& b : rig.bearings)
      if (b.shaft == shaft) return b.stiffness_scale;
    return 1.0;
  };
  k.mesh_stiffness_scale = readPrior(c, w, "mesh_stiffness_scale", {rig.mesh_stiffness_scale, 0.2},
                                     kScaleLowest, kScaleBound);
  k.pinion_bearing_scale =
      readPrior(c, w, "pinion_bearing_scale", {shaftScale(0), 0.3}, kScaleLowest, kScaleBound);
  k.gear_bearing_scale =
      readPrior(c, w, "gear_bearing_scale", {shaftScale(1), 0.3}, kScaleLowest, kScaleBound);
  const double tp = rig.anti_backlash.preload_torque;
  k.preload_torque = readPrior(c, w, "preload_torque", {tp, 0.2 * tp}, 0.0, 1e6);
  k.te_offset = readPrior(c, w, "te_offset", {0.0, 1e-6}, -1e-3, 1e-3);
  k.baseline_torque = readDouble(c, w, "baseline_torque", k.baseline_torque);
  k.torque_band = readDouble(c, w, "torque_band", k.torque_band);
  k.min_speed_rpm = readDouble(c, w, "min_speed_rpm", k.min_speed_rpm);
  k.max_mesh_to_natural = readDouble(c, w, "max_mesh_to_natural", k.max_mesh_to_natural);
  k.gate = readDouble(c, w, "gate", k.gate);
  k.model_error = readDouble(c, w, "model_error", k.model_error);
  k.modal_model_error = readDouble(c, w, "modal_model_error", k.modal_model_error);
  k.te_noise_floor = readDouble(c, w, "te_noise_floor", k.te_noise_floor);
  k.drift = readDouble(c, w, "drift", k.drift);
  k.reference_torque = readDouble(c, w, "reference_torque", k.reference_torque);
  requireNonNegative(key(w, "baseline_torque"), k.baseline_torque);
  requirePositive(key(w, "torque_band"), k.torque_band);
  requireNonNegative(key(w, "min_speed_rpm"), k.min_speed_rpm);
  requireInHalfOpenRange(key(w, "max_mesh_to_natural"), k.max_mesh_to_natural, 1e-6, 1.0);
  requirePositive(key(w, "gate"), k.gate);
  requireInHalfOpenRange(key(w, "model_error"), k.model_error, 0.0, 1.0);
  requireInHalfOpenRange(key(w, "modal_model_error"), k.modal_model_error, 0.0, 1.0);
  requirePositive(key(w, "te_noise_floor"), k.te_noise_floor);
  requireInHalfOpenRange(key(w, "drift"), k.drift, 0.0, 1.0);
  requirePositive(key(w, "reference_torque"), k.reference_torque);
}

static void parseDynamics(const YAML::Node& root, const std::string& file, RigConfig& rig) {
  const YAML::Node d = optionalBlock(root, file, "dynamics", kDynamicsKeys);
  if (!d) return;
  const std::string w = file + ": dynamics";
  DynamicsConfig& c = rig.dynamics;
  c.present = true;
  c.pinion_mass = readDouble(d, w, "pinion_mass");
  c.gear_mass = readDouble(d, w, "gear_mass");
  c.pinion_inertia = readDouble(d, w, "pinion_inertia");
  c.gear_inertia = readDouble(d, w, "gear_inertia");
  c.mesh_damping_ratio = readDouble(d, w, "mesh_damping_ratio", c.mesh_damping_ratio);
  c.bearing_damping_ratio = readDouble(d, w, "bearing_damping_ratio", c.bearing_damping_ratio);
  c.bearing_clearance = readPair(d, w, "bearing_clearance", c.bearing_clearance);
  c.speed_rpm = readDouble(d, w, "speed_rpm", c.speed_rpm);
  c.transmission_error_amplitude =
      readDouble(d, w, "transmission_error_amplitude", c.transmission_error_amplitude);
  c.backlash = readDouble(d, w, "backlash", c.backlash);
  c.torque = readDouble(d, w, "torque", c.torque);
  withContext(file, [&] { checkDynamics(c); });
}

RigConfig loadGearFile(const std::string& path) {
  const YAML::Node root = loadFile(path);
  if (!root.IsMap()) throw InvalidInput(path + ": needs a top-level mapping with 'gears:'");
  RigConfig rig;
  parseGears(root, path, rig);
  parseDynamics(root, path, rig);
  return rig;
}

BearingSupportConfig loadBearingFile(const std::string& path) {
  const YAML::Node root = loadFile(path);
  if (!root.IsMap() || !root["bearing"])
    throw InvalidInput(path + ": needs a top-level 'bearing:' block");
  BearingSupportConfig cfg = parseBearing(root["bearing"], path + ": bearing");
  cfg.name = readString(root["bearing"], path + ": bearing", "name", "bearing");
  return cfg;
}

RigConfig loadRigFile(const std::string& path) {
  const YAML::Node root = loadFile(path);
  const std::string where = path;
  if (!root.IsMap() || !root["gears"] || !root["bearings"]) {
    throw InvalidInput(path + ": needs top-level 'gears:' and 'bearings:' blocks");
  }
  for (const auto& item : root) {
    const std::string name = keyName(item.first, path);
    if (name != "gears" && name != "bearings" && name != "anti_backlash" && name != "mesh" &&
        name != "dynamics" && name != "calibration") {
      throw InvalidInput(path + ": '" + printable(name) + "': unknown top-level key");
    }
  }
  RigConfig rig;
  parseGears(root, where, rig);
  parseDynamics(root, where, rig);

  const YAML::Node list = root["bearings"];
  if (!list.IsSequence() || list.size() == 0)
    throw InvalidInput(where + ": bearings: must be a non-empty list");
  std::set<std::string> names;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string entry = where + ": bearings[" + std::to_string(i) + "]";
    YAML::Node node = YAML::Clone(list[i]);
    if (!node.IsMap()) throw InvalidInput(entry + ": must be a mapping");
    if (node["file"]) {  // keys of the entry override those of the referenced bearing file
      const std::string name = readString(node, entry, "file", "");
      const std::string file =
          !name.empty() && name[0] == '/' ? name : directoryOf(path) + "/" + name;
      // A refusal of the referenced file names the entry that references it, then the file.
      const std::string ref = entry + ".file = '" + name + "'";
      YAML::Node base;
      try {
        base = loadFile(file);
      } catch (const InvalidInput& e) {
        throw InvalidInput(ref + ": " + e.what());
      }
      if (!base.IsMap() || !base["bearing"])
        throw InvalidInput(ref + ": " + file + ": needs a top-level 'bearing:' block");
      if (!base["bearing"].IsMap())
        throw InvalidInput(ref + ": " + file + ": bearing: must be a mapping of bearing keys");
      YAML::Node merged = YAML::Clone(base["bearing"]);
      for (const auto& kv : node) {
        const std::string k = keyName(kv.first, entry);
        if (k != "file") merged[k] = kv.second;
      }
      node = merged;
    }
    BearingSupportConfig cfg = parseBearing(node, entry);
    cfg.name = readString(node, entry, "name", "");
    if (cfg.name.empty()) throw InvalidInput(entry + ".name: required");
    if (!names.insert(cfg.name).second)
      throw InvalidInput(entry + ".name = '" + cfg.name + "': duplicate name");
    const std::string shaft = readString(node, entry, "shaft", "pinion");
    if (shaft != "pinion" && shaft != "gear")
      throw InvalidInput(entry + ".shaft = '" + shaft + "': must be 'pinion' or 'gear'");
    cfg.shaft = shaft == "pinion" ? 0 : 1;
    cfg.mesh_load_share = readDouble(node, entry, "mesh_load_share", 1.0);
    requireInHalfOpenRange(entry + ".mesh_load_share", cfg.mesh_load_share, 0.0, 1.0 + 1e-12);
    cfg.stiffness_scale = readDouble(node, entry, "stiffness_scale", 1.0);
    requireInHalfOpenRange(entry + ".stiffness_scale", cfg.stiffness_scale, kScaleLowest,
                           kScaleBound);
    rig.bearings.push_back(cfg);
  }
  parseCalibration(root, where, rig);
  return rig;
}

}  // namespace drivetrain_stiffness

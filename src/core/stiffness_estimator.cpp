#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

void requireLoadTolerance(std::string_view field, double value) {
  requireInClosedRange(field, value, 0.0, kMaxLoadTolerance);
}

void EstimatorLimits::validate(std::string_view load_tolerance_field) const {
  requirePositive("max_abs_torque", max_abs_torque);
  requirePositive("max_preload", max_preload);
  requirePositive("max_interference", max_interference);
  requireLoadTolerance(load_tolerance_field, load_tolerance);
}

StiffnessEstimator::StiffnessEstimator(const RigConfig& rig, const EstimatorLimits& limits)
    : StiffnessEstimator(std::make_shared<const RigConfig>(rig), limits) {}

StiffnessEstimator::StiffnessEstimator(std::shared_ptr<const RigConfig> rig,
                                       const EstimatorLimits& limits)
    : rig_(std::move(rig)), limits_(limits) {
  if (!rig_)
    throw std::invalid_argument("StiffnessEstimator: no rig");  // a caller's bug, not bad data
  mesh_ = std::make_shared<const AntiBacklashMesh>(*rig_);
  limits.validate();
  if (rig_->bearings.empty()) throw InvalidInput("bearings: at least one support is required");
  for (const BearingSupportConfig& b : rig_->bearings) {
    requireInHalfOpenRange("bearings[" + b.name + "].stiffness_scale", b.stiffness_scale, 0.05,
                           20.0);
  }
  // Period means of k1 and k_chain (the table's exact ones, as meanMeshStiffness takes them): they
  // decide the flank state of the mean stiffness.
  mean_k1_kchain_[0] = mesh_->periodMeans().k1;
  mean_k1_kchain_[1] = mesh_->periodMeans().k_chain;
  reset();
}

MeshEstimate StiffnessEstimator::meshAt(double signed_mesh_force, double pinion_angle) const {
  MeshEstimate m;
  m.phase = mesh_->geometry().phase(pinion_angle);
  m.current = mesh_->at(m.phase, signed_mesh_force);
  const double k1 = mean_k1_kchain_[0], kc = mean_k1_kchain_[1];
  switch (mesh_->flankContact(signed_mesh_force, k1, kc)) {
    case FlankContact::kBoth: m.mean = k1 + kc; break;
    case FlankContact::kDriveOnly: m.mean = k1; break;
    case FlankContact::kBackOnly: m.mean = kc; break;
  }
  return m;
}

long StiffnessEstimator::nextSupportsRevision() {
  static std::atomic<long> next{0};
  return ++next;
}

std::unique_ptr<BearingSupport> StiffnessEstimator::build(const BearingSupportConfig& c) {
  return std::make_unique<BearingSupport>(c.spec, c.arrangement, c.axial_preload, c.interference,
                                          c.tilt);
}

const StiffnessEstimate& StiffnessEstimator::reset() {
  std::vector<Support> supports;
  for (const BearingSupportConfig& c : rig_->bearings) {
    std::unique_ptr<BearingSupport> model = build(c);
    // The spare starts as a copy: setPreloads assigns new geometry into it, never builds one.
    auto spare = std::make_unique<BearingSupport>(*model);
    supports.push_back({c, std::move(model), std::move(spare)});
  }
  estimate_ = solveAll(0.0, 0.0, supports);
  supports_ = std::move(supports);
  workspace_.resize(supports_.size());
  // The mesh phase a preload is solved at (setPreloads) is the last torque's: a reset estimator is
  // a fresh one, at angle 0, not at the angle of the run before the reset.
  last_pinion_angle_ = 0.0;
  supports_revision_ = nextSupportsRevision();
  return estimate_;
}

StiffnessEstimate StiffnessEstimator::solveAll(double torque, double pinion_angle,
                                               const std::vector<Support>& supports) const {
  StiffnessEstimate next;
  next.torque = torque;
  const double signed_force = meshForce(rig_->gears, 0, torque);
  next.mesh_force = std::abs(signed_force);
  next.mesh = meshAt(signed_force, pinion_angle);
  for (std::size_t i = 0; i < supports.size(); ++i) {
    const Support& s = supports[i];
    SupportEstimate e;
    e.name = s.config.name;
    e.radial_load = radialLoad(s.config, next.mesh_force);
    e.axial_load = s.config.arrangement == Arrangement::kSingle ? s.config.axial_preload : 0.0;
    Vector5d load = Vector5d::Zero();
    load[kUx] = e.radial_load;
    try {
      e.solution = s.model->solve(load);  // a new model: cold start
    } catch (const UnreachableLoad& error) {
      throw UnreachableLoad(s.config.name + ": " + error.what());
    }
    e.solution.stiffness *= s.config.stiffness_scale;  // see SupportEstimate
    next.supports.push_back(std::move(e));
  }
  return next;
}

void StiffnessEstimator::validateTorque(double torque) const {
  requireFinite("torque", torque);
  if (std::abs(torque) > limits_.max_abs_torque) {
    throwInvalid("torque", torque,
                 "exceeds max_abs_torque = " + formatValue(limits_.max_abs_torque) + " N·m");
  }
}

void StiffnessEstimator::validatePreloads(const std::vector<PreloadSetting>& settings) const {
  for (const PreloadSetting& p : settings) {
    if (supportIndex(p.name) == supports_.size()) {
      throw InvalidInput("preload.name = '" + p.name + "': no such bearing support");
    }
    auto check = [&](const char* field, double value, double limit) {
      // The name is built only on failure: this runs at every preload input (twice).
      if (std::isfinite(value) && value >= 0.0 && value <= limit) return;
      const std::string name = "preload[" + p.name + "]." + field;
      requireNonNegative(name, value);
      throwInvalid(name, value, "exceeds the limit " + formatValue(limit));
    };
    check("axial_preload", p.axial_preload, limits_.max_preload);
    check("radial_preload", p.radial_preload, limits_.max_preload);
    check("inner_interference", p.inner_interference, limits_.max_interference);
    check("outer_interference", p.outer_interference, limits_.max_interference);
  }
}

std::size_t StiffnessEstimator::supportIndex(const std::string& name) const {
  std::size_t i = 0;
  while (i < supports_.size() && supports_[i].config.name != name) ++i;
  return i;
}

double StiffnessEstimator::radialLoad(const BearingSupportConfig& c, double mesh_force) {
  return c.radial_preload + c.mesh_load_share * mesh_force;
}

bool StiffnessEstimator::solutionStands(std::size_t i, double radial_load) const {
  if (limits_.load_tolerance <= 0.0 || i >= estimate_.supports.size() || i >= supports_.size())
    return false;
  const SupportEstimate& last = estimate_.supports[i];
  return std::abs(radial_load - last.radial_load) <=
         limits_.load_tolerance * (last.radial_load + supports_[i].config.axial_preload);
}

const StiffnessEstimate& StiffnessEstimator::setTorque(double torque, double pinion_angle) {
  validateTorque(torque);
  requireFinite("pinion_angle", pinion_angle);
  const double signed_force = meshForce(rig_->gears, 0, torque);
  const double mesh_force = std::abs(signed_force);
  // In place and all or nothing, with no allocation in steady state: the supports whose load moved
  // past ~load_tolerance are solved into their workspace (warm-started from their last solution,
  // as solveAll would), the mesh is looked up, and only when nothing threw are the new solutions
  // swapped in (a swap of storage, not a copy). The numbers are solveAll's.
  const std::size_t n = supports_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Support& s = supports_[i];
    Workspace& w = workspace_[i];
    w.radial_load = radialLoad(s.config, mesh_force);
    w.solved = !solutionStands(i, w.radial_load);
    if (!w.solved) continue;
    Vector5d load = Vector5d::Zero();
    load[kUx] = w.radial_load;
    try {
      s.model->solve(load, &estimate_.supports[i].solution.displacement, w.solution);
    } catch (const UnreachableLoad& error) {
      throw UnreachableLoad(s.config.name + ": " + error.what());
    }
    w.solution.stiffness *= s.config.stiffness_scale;
  }
  const MeshEstimate mesh = meshAt(signed_force, pinion_angle);
  for (std::size_t i = 0; i < n; ++i) {
    Workspace& w = workspace_[i];
    if (!w.solved) continue;
    std::swap(estimate_.supports[i].solution, w.solution);
    estimate_.supports[i].radial_load = w.radial_load;
  }
  estimate_.torque = torque;
  estimate_.mesh_force = mesh_force;
  estimate_.mesh = mesh;
  last_pinion_angle_ = pinion_angle;
  return estimate_;
}

const StiffnessEstimate& StiffnessEstimator::setPreloads(
    const std::vector<PreloadSetting>& settings) {
  validatePreloads(settings);
  // In place and all or nothing, with no allocation in steady state, as setTorque: the settings are
  // staged in the workspaces (a support named twice takes its last), a support whose geometry
  // changed (axial preload or interference) is rebuilt into its spare model, every support is
  // solved into its workspace, and only when nothing threw are the settings, models and solutions
  // swapped in. The numbers are those of building the changed supports anew and solving all: a
  // rebuilt support is cold-started, the others warm-started from their last solution, and one
  // whose model and radial preload are unchanged keeps its solution within ~load_tolerance.
  stagePreloads(settings);
  const double signed_force = meshForce(rig_->gears, 0, estimate_.torque);
  const double mesh_force = std::abs(signed_force);
  const MeshEstimate mesh = meshAt(signed_force, last_pinion_angle_);
  solveStaged(mesh_force);
  commitStaged();
  supports_revision_ = nextSupportsRevision();
  estimate_.mesh_force = mesh_force;
  estimate_.mesh = mesh;
  return estimate_;
}

void StiffnessEstimator::stagePreloads(const std::vector<PreloadSetting>& settings) {
  const std::size_t n = supports_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const BearingSupportConfig& c = supports_[i].config;
    Workspace& w = workspace_[i];
    w.axial_preload = c.axial_preload;
    w.radial_preload = c.radial_preload;
    w.interference = c.interference;
    w.rebuilt = false;
  }
  for (const PreloadSetting& p : settings) {
    const std::size_t i = supportIndex(p.name);  // known: setPreloads validated it
    Support& s = supports_[i];
    Workspace& w = workspace_[i];
    const bool geometry_changed = w.axial_preload != p.axial_preload ||
                                  w.interference.inner != p.inner_interference ||
                                  w.interference.outer != p.outer_interference;
    w.axial_preload = p.axial_preload;
    w.radial_preload = p.radial_preload;
    w.interference = {p.inner_interference, p.outer_interference};
    if (!geometry_changed) continue;
    const BearingSupportConfig& c = s.config;
    try {
      s.spare->assign(c.spec, c.arrangement, w.axial_preload, w.interference, c.tilt);
    } catch (const InvalidInput& e) {
      throw InvalidInput("preload[" + p.name + "]. " + e.what());
    } catch (const UnreachableLoad& e) {
      throw UnreachableLoad("preload[" + p.name + "]. " + e.what());
    }
    w.rebuilt = true;
  }
}

void StiffnessEstimator::solveStaged(double mesh_force) {
  const std::size_t n = supports_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Support& s = supports_[i];
    Workspace& w = workspace_[i];
    w.radial_load =
        w.radial_preload + s.config.mesh_load_share * mesh_force;  // radialLoad(), new preload
    const bool unchanged =
        !w.rebuilt && w.radial_preload == s.config.radial_preload;  // model and radial preload
    w.solved = !(unchanged && solutionStands(i, w.radial_load));
    if (!w.solved) continue;
    Vector5d load = Vector5d::Zero();
    load[kUx] = w.radial_load;
    // Warm start from the previous solution of the same support when its model is unchanged.
    const Vector5d* start = w.rebuilt ? nullptr : &estimate_.supports[i].solution.displacement;
    try {
      (w.rebuilt ? *s.spare : *s.model).solve(load, start, w.solution);
    } catch (const UnreachableLoad& error) {
      throw UnreachableLoad(s.config.name + ": " + error.what());
    }
    w.solution.stiffness *= s.config.stiffness_scale;  // see SupportEstimate
  }
}

void StiffnessEstimator::commitStaged() {
  const std::size_t n = supports_.size();
  for (std::size_t i = 0; i < n; ++i) {
    Support& s = supports_[i];
    Workspace& w = workspace_[i];
    s.config.axial_preload = w.axial_preload;
    s.config.radial_preload = w.radial_preload;
    s.config.interference = w.interference;
    if (w.rebuilt) std::swap(s.model, s.spare);  // the old model becomes the next spare
    if (!w.solved) continue;
    SupportEstimate& e = estimate_.supports[i];
    std::swap(e.solution, w.solution);
    e.radial_load = w.radial_load;
    e.axial_load = s.config.arrangement == Arrangement::kSingle ? s.config.axial_preload : 0.0;
  }
}

std::array<double, 2> StiffnessEstimator::shaftRadialStiffness() const {
  std::array<double, 2> k{{0.0, 0.0}};
  for (std::size_t i = 0; i < estimate_.supports.size(); ++i)
    k[rig_->bearings[i].shaft] += estimate_.supports[i].solution.radialStiffness();
  return k;
}

}  // namespace drivetrain_stiffness

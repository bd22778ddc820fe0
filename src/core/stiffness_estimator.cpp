#include "drivetrain_stiffness/core/stiffness_estimator.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

StiffnessEstimator::StiffnessEstimator(const RigConfig& rig, const EstimatorLimits& limits)
    : rig_(rig), limits_(limits), mesh_(std::make_shared<const AntiBacklashMesh>(rig)) {
  requirePositive("max_abs_torque", limits.max_abs_torque);
  requirePositive("max_preload", limits.max_preload);
  requirePositive("max_interference", limits.max_interference);
  requireNonNegative("load_tolerance", limits.load_tolerance);
  if (limits.load_tolerance > 0.1) throwInvalid("load_tolerance", limits.load_tolerance, "must be <= 0.1");
  if (rig.bearings.empty()) throw InvalidInput("bearings: at least one support is required");
  for (const BearingSupportConfig& b : rig.bearings) {
    requireInHalfOpenRange("bearings[" + b.name + "].stiffness_scale", b.stiffness_scale, 0.05, 20.0);
  }
  // Period means of k1 and k_chain, computed once: they decide the flank state of the mean
  // stiffness (the table itself is fixed until the gear parameters change).
  const int n = 512;
  for (int i = 0; i < n; ++i) {
    const CompositeMesh c = mesh_->at((i + 0.5) / n, 0.0);
    mean_k1_kchain_[0] += c.k1 / n;
    mean_k1_kchain_[1] += c.k_chain / n;
  }
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

std::shared_ptr<const BearingSupport> StiffnessEstimator::build(const BearingSupportConfig& c) {
  return std::make_shared<const BearingSupport>(c.spec, c.arrangement, c.axial_preload, c.interference, c.tilt);
}

const StiffnessEstimate& StiffnessEstimator::reset() {
  std::vector<Support> supports;
  for (const BearingSupportConfig& c : rig_.bearings) supports.push_back({c, build(c)});
  estimate_ = solveAll(0.0, 0.0, supports);
  supports_ = std::move(supports);
  workspace_.resize(supports_.size());
  return estimate_;
}

StiffnessEstimate StiffnessEstimator::solveAll(double torque, double pinion_angle,
                                               const std::vector<Support>& supports) const {
  StiffnessEstimate next;
  next.torque = torque;
  const double signed_force = meshForce(rig_.gears, 0, torque);
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
    if (solutionStands(i, s, e.radial_load)) {
      next.supports.push_back(estimate_.supports[i]);  // the solution and the load it was solved for
      continue;
    }
    // Warm start from the previous solution of the same support when its model is unchanged.
    const bool warm = i < estimate_.supports.size() && i < supports_.size() && supports_[i].model == s.model;
    const Vector5d* start = warm ? &estimate_.supports[i].solution.displacement : nullptr;
    try {
      e.solution = s.model->solve(load, start);
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
    throwInvalid("torque", torque, "exceeds max_abs_torque = " + formatValue(limits_.max_abs_torque) + " N·m");
  }
}

void StiffnessEstimator::validatePreloads(const std::vector<PreloadSetting>& settings) const {
  for (const PreloadSetting& p : settings) {
    const bool known = std::any_of(supports_.begin(), supports_.end(), [&](const Support& s) { return s.config.name == p.name; });
    if (!known) throw InvalidInput("preload.name = '" + p.name + "': no such bearing support");
    const std::string prefix = "preload[" + p.name + "].";
    auto check = [&](const std::string& field, double value, double limit) {
      requireNonNegative(prefix + field, value);
      if (value > limit) throwInvalid(prefix + field, value, "exceeds the limit " + formatValue(limit));
    };
    check("axial_preload", p.axial_preload, limits_.max_preload);
    check("radial_preload", p.radial_preload, limits_.max_preload);
    check("inner_interference", p.inner_interference, limits_.max_interference);
    check("outer_interference", p.outer_interference, limits_.max_interference);
  }
}

double StiffnessEstimator::radialLoad(const BearingSupportConfig& c, double mesh_force) {
  return c.radial_preload + c.mesh_load_share * mesh_force;
}

bool StiffnessEstimator::solutionStands(std::size_t i, const Support& s, double radial_load) const {
  if (limits_.load_tolerance <= 0.0 || i >= estimate_.supports.size() || i >= supports_.size()) return false;
  if (supports_[i].model != s.model || supports_[i].config.radial_preload != s.config.radial_preload) return false;
  const SupportEstimate& last = estimate_.supports[i];
  return std::abs(radial_load - last.radial_load) <= limits_.load_tolerance * (last.radial_load + s.config.axial_preload);
}

const StiffnessEstimate& StiffnessEstimator::setTorque(double torque, double pinion_angle) {
  validateTorque(torque);
  requireFinite("pinion_angle", pinion_angle);
  const double signed_force = meshForce(rig_.gears, 0, torque);
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
    w.solved = !solutionStands(i, s, w.radial_load);
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

const StiffnessEstimate& StiffnessEstimator::setPreloads(const std::vector<PreloadSetting>& settings) {
  validatePreloads(settings);
  std::vector<Support> next = supports_;
  for (const PreloadSetting& p : settings) {
    auto it = std::find_if(next.begin(), next.end(), [&](const Support& s) { return s.config.name == p.name; });
    const std::string prefix = "preload[" + p.name + "].";
    BearingSupportConfig c = it->config;
    const bool geometry_changed = c.axial_preload != p.axial_preload || c.interference.inner != p.inner_interference ||
                                  c.interference.outer != p.outer_interference;
    c.axial_preload = p.axial_preload;
    c.radial_preload = p.radial_preload;
    c.interference = {p.inner_interference, p.outer_interference};
    try {
      *it = {c, geometry_changed ? build(c) : it->model};
    } catch (const InvalidInput& e) {
      throw InvalidInput(prefix + " " + e.what());
    } catch (const UnreachableLoad& e) {
      throw UnreachableLoad(prefix + " " + e.what());
    }
  }
  estimate_ = solveAll(estimate_.torque, last_pinion_angle_, next);
  supports_ = std::move(next);
  workspace_.resize(supports_.size());
  return estimate_;
}

std::array<double, 2> StiffnessEstimator::shaftRadialStiffness() const {
  std::array<double, 2> k{{0.0, 0.0}};
  for (std::size_t i = 0; i < estimate_.supports.size(); ++i)
    k[rig_.bearings[i].shaft] += estimate_.supports[i].solution.radialStiffness();
  return k;
}

}  // namespace drivetrain_stiffness

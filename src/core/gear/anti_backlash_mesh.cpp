#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

const char* toString(FlankContact contact) {
  switch (contact) {
    case FlankContact::kBoth: return "both";
    case FlankContact::kDriveOnly: return "drive_only";
    case FlankContact::kBackOnly: return "back_only";
  }
  return "?";
}

void validateAntiBacklash(const AntiBacklashSpec& spec) {
  // The upper bounds are past anything built (tooth pairs are ~1e9 N/m); at 1e308 the flank forces
  // overflow into a NaN mesh stiffness instead of a refusal.
  requireNonNegative("anti_backlash.spring_stiffness", spec.spring_stiffness);   // 0: ordinary gear
  requireAtMost("anti_backlash.spring_stiffness", spec.spring_stiffness, 1e13);  // [N/m]
  requireNonNegative("anti_backlash.preload_torque", spec.preload_torque);
  requireAtMost("anti_backlash.preload_torque", spec.preload_torque, 1e6);  // [N m]
  requireNonNegative("anti_backlash.loaded_gear_face_width", spec.loaded_gear_face_width);
  requireAtMost("anti_backlash.loaded_gear_face_width", spec.loaded_gear_face_width,
                10.0);  // [m], as gears.face_width
}

AntiBacklashMesh::AntiBacklashMesh(const GearPairSpec& gears, const AntiBacklashSpec& spec,
                                   MeshStiffnessModel model, int samples, double stiffness_scale)
    : geometry_(gears), spec_(spec), model_(model), scale_(stiffness_scale) {
  validateAntiBacklash(spec);
  // A calibrated scale is within a factor of a few of the drawing's; 0 or 1e3 is a typo.
  requireInHalfOpenRange("mesh.stiffness_scale", stiffness_scale, 0.05, 20.0);
  preload_force_ = spec.preload_torque / geometry_.baseRadius(1);
  const auto drive_model = makeToothPairStiffness(model, geometry_, gears.face_width);
  verified_ = drive_model->verified();
  drive_ = std::make_unique<MeshStiffnessTable>(geometry_, *drive_model, samples);
  const double width2 =
      spec.loaded_gear_face_width > 0.0 ? spec.loaded_gear_face_width : gears.face_width;
  const auto back_model = makeToothPairStiffness(model, geometry_, width2);
  back_ = std::make_unique<MeshStiffnessTable>(geometry_, *back_model, samples);

  // Switching phases: drive pairs change at 0 and eps - 1; back pairs where a back pair reaches
  // s_E or s_A (s' = origin - (phi + k) p_b). Between them every pair moves smoothly.
  const SpurGearGeometry& g = geometry_;
  auto wrap = [](double x) { return x - std::floor(x); };
  breaks_ = {0.0, wrap(g.contactRatio() - 1.0)};
  std::array<double, 3> s_probe;
  g.backPairs(0.0, s_probe);
  const double back_origin = s_probe[0];  // s' of some back pair at phase 0
  if (spec_.spring_stiffness > 0.0) {
    breaks_.push_back(wrap((back_origin - g.pathEnd()) / g.basePitch()));
    breaks_.push_back(wrap((back_origin - g.pathStart()) / g.basePitch()));
  }
  std::sort(breaks_.begin(), breaks_.end());
  breaks_.erase(
      std::unique(breaks_.begin(), breaks_.end(), [](double a, double b) { return b - a < 1e-12; }),
      breaks_.end());
  const int per_segment = std::max(16, samples / 2);
  for (std::size_t i = 0; i < breaks_.size(); ++i) {
    const double a = breaks_[i], b = i + 1 < breaks_.size() ? breaks_[i + 1] : 1.0;
    if (b - a < 1e-12) continue;
    Segment seg;
    seg.start = a;
    seg.scale = (per_segment - 1) / (b - a);
    const double inset = 1e-9 * (b - a);  // evaluate just inside the segment at its ends
    const CompositeMesh mid = exactAt(0.5 * (a + b), 0.0);
    seg.drive_pairs = mid.drive_pairs;
    seg.back_pairs = mid.back_pairs;
    for (int j = 0; j < per_segment; ++j) {
      const double phi = std::clamp(a + j / seg.scale, a + inset, b - inset);
      const CompositeMesh c = exactAt(phi, 0.0);
      seg.values.push_back({c.k1, c.k2, c.k_chain});
    }
    // The segment's exact integral: trapezoid over its nodes, spacing (b - a) / (n - 1).
    const double h = (b - a) / (per_segment - 1);
    for (int j = 0; j < per_segment; ++j) {
      const double w = (j == 0 || j == per_segment - 1) ? 0.5 * h : h;
      means_.k1 += w * seg.values[j][0];
      means_.k2 += w * seg.values[j][1];
      means_.k_chain += w * seg.values[j][2];
    }
    segments_.push_back(std::move(seg));
  }
}

AntiBacklashMesh::AntiBacklashMesh(const RigConfig& rig)
    : AntiBacklashMesh(rig.gears, rig.anti_backlash, rig.mesh_model, rig.mesh_samples,
                       rig.mesh_stiffness_scale) {}

FlankContact AntiBacklashMesh::flankContact(double mesh_force, double k1, double k_chain,
                                            double preload_force) {
  if (!(k_chain > 0.0)) return FlankContact::kDriveOnly;  // no loaded half: an ordinary gear
  // F_m > F_p (1 + k1/k_c) and F_m < -F_p (1 + k_c/k1), multiplied out (k1, k_c > 0): no division
  // on the lookup path.
  const double sum = k1 + k_chain;
  if (mesh_force * k_chain > preload_force * sum) return FlankContact::kDriveOnly;
  if (mesh_force * k1 < -preload_force * sum) return FlankContact::kBackOnly;
  return FlankContact::kBoth;
}

std::vector<double> AntiBacklashMesh::tableNodePhases() const {
  std::vector<double> nodes;
  for (const Segment& seg : segments_) {
    for (std::size_t j = 0; j < seg.values.size(); ++j) nodes.push_back(seg.start + j / seg.scale);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(
      std::unique(nodes.begin(), nodes.end(), [](double a, double b) { return b - a < 1e-12; }),
      nodes.end());
  while (!nodes.empty() && nodes.back() >= 1.0) nodes.pop_back();
  return nodes;
}

void AntiBacklashMesh::applyFlankState(CompositeMesh& c, double mesh_force) const {
  c.contact = flankContact(mesh_force, c.k1, c.k_chain);
  switch (c.contact) {
    case FlankContact::kBoth: c.composite = c.k1 + c.k_chain; break;  // seed 000 eq 1
    case FlankContact::kDriveOnly: c.composite = c.k1; break;
    case FlankContact::kBackOnly: c.composite = c.k_chain; break;
  }
}

CompositeMesh AntiBacklashMesh::at(double phase, double mesh_force) const {
  // Hot path: check without building the field-name string unless the check fails.
  if (!std::isfinite(mesh_force)) throwInvalid("mesh_force", mesh_force, "must be a finite number");
  if (!(phase >= 0.0 && phase < 1.0)) {
    if (!std::isfinite(phase)) throwInvalid("phase", phase, "must be a finite number");
    phase -= std::floor(phase);
  }
  std::size_t k = segments_.size() - 1;
  while (k > 0 && phase < segments_[k].start) --k;
  const Segment& seg = segments_[k];
  const double u = (phase - seg.start) * seg.scale;
  const std::size_t i = std::min(static_cast<std::size_t>(u), seg.values.size() - 2);
  const double w = u - static_cast<double>(i);
  const auto& lo = seg.values[i];
  const auto& hi = seg.values[i + 1];
  CompositeMesh out;
  out.k1 = lo[0] + w * (hi[0] - lo[0]);
  out.k2 = lo[1] + w * (hi[1] - lo[1]);
  out.k_chain = lo[2] + w * (hi[2] - lo[2]);
  out.drive_pairs = seg.drive_pairs;
  out.back_pairs = seg.back_pairs;
  applyFlankState(out, mesh_force);
  return out;
}

CompositeMesh AntiBacklashMesh::exactAt(double phase, double mesh_force) const {
  if (!std::isfinite(mesh_force)) throwInvalid("mesh_force", mesh_force, "must be a finite number");
  CompositeMesh out;
  std::array<double, 3> s;
  out.drive_pairs = geometry_.drivePairs(phase, s);
  for (int i = 0; i < out.drive_pairs; ++i) out.k1 += scale_ * drive_->pair(s[i]);
  out.back_pairs = geometry_.backPairs(phase, s);
  for (int i = 0; i < out.back_pairs; ++i) out.k2 += scale_ * back_->pair(s[i]);
  if (spec_.spring_stiffness > 0.0) {
    out.k_chain = spec_.spring_stiffness * out.k2 / (spec_.spring_stiffness + out.k2);
  } else {
    out.k2 = 0.0;
    out.back_pairs = 0;
  }
  applyFlankState(out, mesh_force);
  return out;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/calibration/static_te_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

const char* calibrationName(int index) {
  switch (index) {
    case kMeshScale: return "mesh_stiffness_scale";
    case kPinionBearingScale: return "pinion_bearing_scale";
    case kGearBearingScale: return "gear_bearing_scale";
    case kPreloadTorque: return "preload_torque";
    case kTeOffset: return "te_offset";
    default: return "?";
  }
}

StaticTeModel::StaticTeModel(const RigConfig& rig,
                             std::shared_ptr<const AntiBacklashMesh> rig_mesh) {
  // The drawing's tooth stiffness (scale 1): the calibrated scale multiplies it. The rig's own
  // table is that table when the rig's scale is 1 (the same constructor arguments, so the same
  // numbers); a rig with another scale needs one at scale 1 of its own.
  if (rig_mesh && rig_mesh->stiffnessScale() == 1.0) {
    unit_ = std::move(rig_mesh);
  } else {
    unit_ = std::make_shared<const AntiBacklashMesh>(rig.gears, rig.anti_backlash, rig.mesh_model,
                                                     rig.mesh_samples, 1.0);
  }
  const AntiBacklashMesh& mesh = *unit_;
  switches_ = mesh.switchingPhases();
  spring_ = rig.anti_backlash.spring_stiffness;
  base_radius_ = {mesh.geometry().baseRadius(0), mesh.geometry().baseRadius(1)};
  // Midpoint rule inside each interval between switching phases, where k1 and k2 are smooth: the
  // steps add no error (a grid across a step would be off by up to step / points per harmonic).
  std::vector<double> breaks = switches_;
  breaks.push_back(1.0);
  constexpr int kPerInterval = 64;
  for (std::size_t s = 0; s + 1 < breaks.size(); ++s) {
    const double a = breaks[s], width = breaks[s + 1] - a;
    if (width <= 1e-12) continue;
    for (int i = 0; i < kPerInterval; ++i) {
      GridPoint g;
      g.phase = a + (i + 0.5) * width / kPerInterval;
      g.weight = width / kPerInterval;
      const CompositeMesh c = mesh.exactAt(g.phase, 0.0);
      g.k1 = c.k1;
      g.k2 = c.k2;
      for (int k = 0; k < kFeatureHarmonics; ++k)
        g.basis[k] = 2.0 * std::polar(1.0, -kTwoPi * (k + 1) * g.phase);
      grid_.push_back(g);
    }
  }
  for (BothFlankMean& c : both_flank_means_)
    c.points.resize(grid_.size());  // no allocation on the bands' path
}

bool StaticTeModel::nearSwitch(double phase, double guard) const {
  const double ph = phase - std::floor(phase);
  for (double s : switches_) {
    const double d = std::abs(ph - s);
    if (std::min(d, 1.0 - d) < guard) return true;
  }
  return false;
}

void StaticTeModel::prepare(const PhaseHistogram& histogram, long count, SampledPhases& out) const {
  out.size = 0;
  out.ok = false;
  if (count <= 0) return;
  const double inv = 1.0 / static_cast<double>(count);
  Eigen::Matrix<double, kProjectionTerms, kProjectionTerms> gram =
      Eigen::Matrix<double, kProjectionTerms, kProjectionTerms>::Zero();
  for (std::size_t b = 0; b < static_cast<std::size_t>(kPhaseBins); ++b) {
    const std::uint32_t n = histogram.count[b];
    if (n == 0) continue;
    const std::size_t i = static_cast<std::size_t>(out.size++);
    const double phase = histogram.phase_sum[b] / n;
    const CompositeMesh m = unit_->at(phase, 0.0);  // the phase table: exact switching phases
    out.weight[i] = n * inv;
    out.k1[i] = m.k1;
    out.k2[i] = m.k2;
    Eigen::Matrix<double, kProjectionTerms, 1>& a = out.basis[i];
    a[0] = 1.0;
    for (int k = 1; k <= (kProjectionTerms - 1) / 2; ++k) {
      a[2 * k - 1] = std::cos(kTwoPi * k * phase);
      a[2 * k] = std::sin(kTwoPi * k * phase);
    }
    gram.noalias() += out.weight[i] * a * a.transpose();
  }
  out.gram.compute(gram);
  out.ok = out.gram.info() == Eigen::Success;
}

FeatureVector StaticTeModel::sampledFeatures(const CalibrationVector& p, double torque,
                                             const std::array<double, 2>& shafts,
                                             double baseline_torque,
                                             const std::array<double, 2>& baseline_shafts,
                                             const SampledPhases& sampled) const {
  const double f = meshForce(torque), f0 = meshForce(baseline_torque);
  const double bearings = bearingTerm(p, shafts) - bearingTerm(p, baseline_shafts);
  Eigen::Matrix<double, kProjectionTerms, 1> b = Eigen::Matrix<double, kProjectionTerms, 1>::Zero();
  for (std::size_t i = 0; i < static_cast<std::size_t>(sampled.size); ++i) {
    const double x = deflection(p, f, sampled.k1[i], sampled.k2[i]) -
                     deflection(p, f0, sampled.k1[i], sampled.k2[i]);
    b.noalias() += (sampled.weight[i] * x) * sampled.basis[i];
  }
  const Eigen::Matrix<double, kProjectionTerms, 1> coef = sampled.gram.solve(b);
  FeatureVector out;
  out[0] = coef[0] + bearings + p[kTeOffset];
  for (int k = 0; k < kFeatureHarmonics; ++k)
    out[1 + k] = std::hypot(coef[1 + 2 * k], coef[2 + 2 * k]);
  return out;
}

double StaticTeModel::meshDeflection(const CalibrationVector& p, double force, int j) const {
  const GridPoint& g = grid_[static_cast<std::size_t>(j)];
  return deflection(p, force, g.k1, g.k2);
}

StaticTeModel::Flanks StaticTeModel::flanks(const CalibrationVector& p, double force, double k1u,
                                            double k2u) const {
  Flanks f;
  f.k1 = p[kMeshScale] * k1u;
  const double k2 = p[kMeshScale] * k2u;
  f.kc = spring_ > 0.0 ? spring_ * k2 / (spring_ + k2) : 0.0;
  f.fp = p[kPreloadTorque] / base_radius_[1];
  f.contact = AntiBacklashMesh::flankContact(force, f.k1, f.kc, f.fp);
  return f;
}

double StaticTeModel::deflection(const CalibrationVector& p, double force, double k1u,
                                 double k2u) const {
  // The three flank states of anti_backlash_mesh.hpp (an ordinary gear: the drive flank only).
  const Flanks f = flanks(p, force, k1u, k2u);
  switch (f.contact) {
    case FlankContact::kDriveOnly: return (force - (f.kc > 0.0 ? f.fp : 0.0)) / f.k1;
    case FlankContact::kBackOnly: return (force + f.fp) / f.kc;
    case FlankContact::kBoth: break;
  }
  return force / (f.k1 + f.kc);
}

double StaticTeModel::bearingTerm(const CalibrationVector& p, const std::array<double, 2>& shafts) {
  return shafts[0] / p[kPinionBearingScale] + shafts[1] / p[kGearBearingScale];
}

void StaticTeModel::shaftDeflection(double torque, const StiffnessEstimator& supports,
                                    std::array<double, 2>& out) {
  // Two memos, both exact (the solves are deterministic functions of the supports' settings and
  // models, which supportsRevision names, and of the torque): the unloaded solutions do not depend
  // on the torque, and the calibrator asks for the same torque at every encoder reading until the
  // next torque message (5 kHz encoders on 1 kHz torque: five times).
  const long revision = supports.supportsRevision();
  if (revision == deflection_memo_.revision && torque == deflection_memo_.torque) {
    out = deflection_memo_.shafts;
    return;
  }
  const double force = std::abs(meshForce(torque));
  const std::size_t n = supports.rig().bearings.size();
  loaded_.resize(n);
  unloaded_.resize(n);
  const bool unloaded_known = revision == deflection_memo_.revision;
  deflection_memo_.revision = 0;  // invalid until this call's solves have all succeeded
  out = {0.0, 0.0};
  Vector5d load = Vector5d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const BearingSupportConfig& c = supports.supportConfig(i);
    const BearingSupport& model = supports.supportModel(i);
    if (!unloaded_known) {
      load[kUx] = c.radial_preload;
      model.solve(load, nullptr, unloaded_[i]);
    }
    load[kUx] = c.radial_preload + c.mesh_load_share * force;
    model.solve(load, &unloaded_[i].displacement, loaded_[i]);
    // The secant deflection of the support under the mesh force, carried to the gear by the lever
    // rule (a rigid shaft: the gear moves by the share-weighted support deflections).
    out[c.shaft] +=
        c.mesh_load_share * (loaded_[i].displacement[kUx] - unloaded_[i].displacement[kUx]);
  }
  if (torque < 0.0) out = {-out[0], -out[1]};
  deflection_memo_ = {revision, torque, out};
}

void StaticTeModel::waveform(const CalibrationVector& p, double torque,
                             const std::array<double, 2>& shafts, double& mean,
                             std::array<std::complex<double>, kFeatureHarmonics>& harmonics) const {
  const double force = meshForce(torque);
  mean = bearingTerm(p, shafts);  // constant over the period: no harmonic
  harmonics.fill({0.0, 0.0});
  for (std::size_t j = 0; j < grid_.size(); ++j) {
    const double delta = meshDeflection(p, force, static_cast<int>(j));
    mean += grid_[j].weight * delta;
    for (int k = 0; k < kFeatureHarmonics; ++k)
      harmonics[k] += grid_[j].weight * delta * grid_[j].basis[k];
  }
}

FeatureVector StaticTeModel::features(const CalibrationVector& p, double torque,
                                      const std::array<double, 2>& shafts, double baseline_torque,
                                      const std::array<double, 2>& baseline_shafts) const {
  double m = 0.0, m0 = 0.0;
  std::array<std::complex<double>, kFeatureHarmonics> c, c0;
  waveform(p, torque, shafts, m, c);
  waveform(p, baseline_torque, baseline_shafts, m0, c0);
  FeatureVector f;
  f[0] = m - m0 + p[kTeOffset];
  for (int k = 0; k < kFeatureHarmonics; ++k) f[1 + k] = std::abs(c[k] - c0[k]);
  return f;
}

double StaticTeModel::at(const CalibrationVector& p, double phase, double torque,
                         const std::array<double, 2>& shafts, double baseline_torque,
                         const std::array<double, 2>& baseline_shafts) const {
  // The grid point whose interval holds the phase (midpoints 1/64 of an interval apart: the
  // per-reading curve for plots; the features use the exact period integrals).
  const double ph = phase - std::floor(phase);
  auto it = std::lower_bound(grid_.begin(), grid_.end(), ph, [](const GridPoint& g, double x) {
    return g.phase + 0.5 * g.weight < x;
  });
  const int j = static_cast<int>(
      std::min<std::size_t>(static_cast<std::size_t>(it - grid_.begin()), grid_.size() - 1));
  const double loaded = meshDeflection(p, meshForce(torque), j) + bearingTerm(p, shafts);
  const double base =
      meshDeflection(p, meshForce(baseline_torque), j) + bearingTerm(p, baseline_shafts);
  return loaded - base + p[kTeOffset];
}

const StaticTeModel::BothFlankMean& StaticTeModel::bothFlankMean(const CalibrationVector& p) const {
  for (const BothFlankMean& c : both_flank_means_) {
    if (c.scale == p[kMeshScale] && c.preload == p[kPreloadTorque]) return c;
  }
  BothFlankMean& c = both_flank_means_[next_both_flank_mean_];
  next_both_flank_mean_ = (next_both_flank_mean_ + 1) % both_flank_means_.size();
  c.scale = p[kMeshScale];
  c.preload = p[kPreloadTorque];
  c.mean = 0.0;
  c.fp = p[kPreloadTorque] / base_radius_[1];  // as flanks() forms F_p
  c.force_low = -std::numeric_limits<double>::infinity();
  c.force_high = std::numeric_limits<double>::infinity();
  c.held_low = 1.0;
  c.held_high = -1.0;
  bool never_both = false;
  for (std::size_t j = 0; j < grid_.size(); ++j) {
    const GridPoint& g = grid_[j];
    const Flanks f = flanks(p, 0.0, g.k1, g.k2);
    FlankPoint& point = c.points[j];
    point = {f.k1, f.kc};
    c.mean += g.weight * (f.k1 + f.kc);  // as meanMeshStiffness sums it: the same bits
    // AntiBacklashMesh::flankContact keeps both flanks for -F_p (1 + k_c/k1) <= F <= F_p (1 +
    // k1/k_c). No loaded half (an ordinary gear): the drive flank alone at any force, no bound. No
    // drive pair in contact: the back half carries the force up to F_p.
    if (f.kc > 0.0) {
      point.above = f.k1 > 0.0 ? f.fp * (f.k1 + f.kc) / f.kc : f.fp;
      if (f.k1 > 0.0) point.below = -f.fp * (f.k1 + f.kc) / f.k1;
    }
    if (!(f.kc > 0.0) || !(f.k1 > 0.0)) {
      never_both = true;  // an ordinary gear (or no tooth): never both flanks
      continue;           // the other points' flank stiffnesses are still wanted
    }
    // The range is taken 1e-12 inside those bounds, far beyond the rounding of its products.
    c.force_high = std::min(c.force_high, point.above * (1.0 - 1e-12));
    c.force_low = std::max(c.force_low, point.below * (1.0 - 1e-12));
  }
  if (never_both) {
    c.force_low = 1.0;
    c.force_high = -1.0;
  }
  return c;
}

double StaticTeModel::meanMeshStiffness(const CalibrationVector& p, double torque) const {
  const double force = meshForce(torque);
  const BothFlankMean& both = bothFlankMean(p);
  if (force >= both.force_low && force <= both.force_high) return both.mean;
  // Above or near a knee the sum depends on the force only through the points' flank states: the
  // last sum holds wherever none of them changes (the stiffness bands ask at every torque input,
  // a noisy torque about one level, at parameters that change once a window).
  if (force >= both.held_low && force <= both.held_high) return both.held_mean;
  // Each point's flank state from the entry's k1, k_c and F_p: flanks() at this force, without
  // its divisions. Around it, the nearest force at which a point's state changes on either side
  // (its bounds, kept with the entry), taken 1e-12 towards this force, far beyond the rounding of
  // flankContact's products (as force_low and force_high).
  double k = 0.0;
  double low = -std::numeric_limits<double>::infinity(),
         high = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < grid_.size(); ++j) {
    const FlankPoint& f = both.points[j];
    const FlankContact contact = AntiBacklashMesh::flankContact(force, f.k1, f.kc, both.fp);
    const double ks = contact == FlankContact::kBoth
                          ? f.k1 + f.kc
                          : (contact == FlankContact::kDriveOnly ? f.k1 : f.kc);
    k += grid_[j].weight * ks;
    for (const double bound : {f.above, f.below}) {
      if (!std::isfinite(bound)) continue;  // no change of state on that side
      if (bound > force) high = std::min(high, bound - 1e-12 * std::abs(bound));
      if (bound < force) low = std::max(low, bound + 1e-12 * std::abs(bound));
      if (bound == force) low = high = force;  // on a bound: this force only
    }
  }
  // The divided bounds and flankContact's products disagree within a few ulps of a bound: a force
  // there can be past a divided bound in the state of the side below it, and its range would then
  // not contain it (nor the states it was summed in). Such a force, and a NaN, hold for itself only
  // (a NaN for none: no comparison with it is true).
  if (!(low <= force && force <= high)) low = high = force;
  both.held_low = low;
  both.held_high = high;
  both.held_mean = k;
  return k;
}

double StaticTeModel::kneeTorque(const CalibrationVector& p) const {
  if (!(spring_ > 0.0)) return 0.0;
  double k1 = 0.0, kc = 0.0;
  for (const GridPoint& g : grid_) {
    k1 += g.weight * p[kMeshScale] * g.k1;
    const double k2 = p[kMeshScale] * g.k2;
    kc += g.weight * spring_ * k2 / (spring_ + k2);
  }
  const double fp = p[kPreloadTorque] / base_radius_[1];
  return fp * (1.0 + k1 / kc) * base_radius_[0];
}

}  // namespace drivetrain_stiffness

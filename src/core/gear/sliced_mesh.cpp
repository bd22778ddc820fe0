#include "drivetrain_stiffness/core/gear/sliced_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

SlicedMesh::SlicedMesh(std::shared_ptr<const AntiBacklashMesh> mesh, int slices)
    : mesh_(std::move(mesh)) {
  if (!mesh_) throw InvalidInput("sliced mesh: no mesh table");
  if (slices < 4 || slices > 65536)
    throwInvalid("motion_slices", slices, "must be in [4, 65536] per mesh period");
  std::vector<double> b;
  for (int j = 0; j < slices; ++j) b.push_back(static_cast<double>(j) / slices);
  for (double s : mesh_->switchingPhases()) b.push_back(s - std::floor(s));
  std::sort(b.begin(), b.end());
  // A switch closer than 1e-9 of a period to a uniform boundary replaces it (no sliver slices).
  for (double x : b) {
    if (bounds_.empty() || x - bounds_.back() > 1e-9) {
      bounds_.push_back(x);
    } else if (x != bounds_.back() &&
               std::find(mesh_->switchingPhases().begin(), mesh_->switchingPhases().end(), x) !=
                   mesh_->switchingPhases().end()) {
      bounds_.back() = x;
    }
  }
  if (bounds_.front() > 0.0) bounds_.insert(bounds_.begin(), 0.0);
  if (1.0 - bounds_.back() <= 1e-9) bounds_.pop_back();
  bounds_.push_back(1.0);
  // Slice means of the phase table: 16-point midpoint rule inside each slice. The table is linear
  // between its nodes, so this is exact up to the nodes inside a slice (a 1/16-slice kink).
  const int n = static_cast<int>(bounds_.size()) - 1;
  k1_.resize(n);
  kc_.resize(n);
  for (int j = 0; j < n; ++j) {
    double s1 = 0.0, sc = 0.0;
    for (int q = 0; q < 16; ++q) {
      const CompositeMesh c =
          mesh_->at(bounds_[j] + (q + 0.5) / 16.0 * (bounds_[j + 1] - bounds_[j]), 0.0);
      s1 += c.k1;
      sc += c.k_chain;
    }
    k1_[j] = s1 / 16.0;
    kc_[j] = mesh_->spec().spring_stiffness > 0.0 ? sc / 16.0 : 0.0;
  }
  anti_backlash_ = mesh_->antiBacklash();
  phasors_.resize(bounds_.size());
  for (std::size_t k = 0; k < bounds_.size(); ++k)
    phasors_[k] = std::polar(1.0, kTwoPi * bounds_[k]);
  phasors_.front() = phasors_.back() =
      1.0;  // phase 0 and 1 turn: sin(2 pi) would round to -2.4e-16
}

std::shared_ptr<const SlicedMesh> SlicedMesh::periodMean(
    std::shared_ptr<const AntiBacklashMesh> mesh) {
  if (!mesh) throw InvalidInput("sliced mesh: no mesh table");
  std::shared_ptr<SlicedMesh> mean(new SlicedMesh());
  mean->mesh_ = std::move(mesh);
  // The table's exact period means, as meanMeshStiffness and the nominal linear_modal take them
  // (AntiBacklashMesh::periodMeans); k_c only with a scissor spring, as the slices above hold it.
  const AntiBacklashMesh::PeriodMeans& m = mean->mesh_->periodMeans();
  const bool spring = mean->mesh_->spec().spring_stiffness > 0.0;
  mean->anti_backlash_ = mean->mesh_->antiBacklash();
  mean->bounds_ = {0.0, 1.0};
  mean->k1_ = {m.k1};
  mean->kc_ = {spring ? m.k_chain : 0.0};
  mean->phasors_ = {1.0, 1.0};
  return mean;
}

int SlicedMesh::sliceAt(double p, bool backward) const {
  // upper_bound: first boundary > p, so bounds_[j] <= p < bounds_[j + 1].
  int j =
      static_cast<int>(std::upper_bound(bounds_.begin(), bounds_.end(), p) - bounds_.begin()) - 1;
  if (backward && j > 0 && p == bounds_[j]) --j;
  if (backward && j == 0 && p == 0.0) j = size() - 1;
  return std::clamp(j, 0, size() - 1);
}

SlicedExcitation::SlicedExcitation(std::shared_ptr<const SlicedMesh> slices, double te_amplitude,
                                   double backlash, double torque_gain, double load_term,
                                   const MeshMotion& motion, double torque)
    : slices_(std::move(slices)),
      te_amplitude_(te_amplitude),
      backlash_(backlash),
      torque_gain_(torque_gain),
      load_term_(load_term),
      motion_(motion),
      torque_(torque) {
  if (!slices_) throw InvalidInput("sliced excitation: no sliced mesh");
  requireNonNegative("transmission_error_amplitude", te_amplitude);
  requireNonNegative("backlash", backlash);
  requireFinite("torque_gain", torque_gain);
  requireFinite("load_term", load_term);
  motion_.validate();
  requireFinite("torque", torque);
}

void SlicedExcitation::at(double t, const MeshMotion& motion, double torque,
                          MeshInstant& out) const {
  const double turns = motion.phaseAt(t);
  out.phase = turns - std::floor(turns);
  // On a boundary the slice the motion enters (the right limit in time): nextSwitch returns times
  // whose phase is on or past the boundary, so this agrees with the events dopri5 steps onto.
  const int j = slices_->sliceAt(out.phase, motion.frequency < 0.0);
  out.k_drive = slices_->k1(j);
  out.k_back = slices_->kChain(j);
  out.preload_force = slices_->mesh().preloadForce();
  out.backlash = backlash_;
  const double w = kTwoPi * motion.frequency;
  out.te = te_amplitude_ * std::sin(kTwoPi * out.phase);
  out.te_rate = te_amplitude_ * w * std::cos(kTwoPi * out.phase);
  out.drive_force = torque_gain_ * torque + load_term_;
}

double SlicedExcitation::nextSwitch(double t, const MeshMotion& motion) const {
  const double f = motion.frequency;
  if (f == 0.0) return std::numeric_limits<double>::infinity();
  const double turns = motion.phaseAt(t);
  double whole = std::floor(turns);
  const double p = turns - whole;
  const SlicedMesh& s = *slices_;
  const int j = s.sliceAt(p, f < 0.0);
  // Backwards from a period boundary (p = 0) the slice is the top one of the period below.
  if (f < 0.0 && p == 0.0) whole -= 1.0;
  const double target = whole + (f > 0.0 ? s.end(j) : s.start(j));
  // The first time whose computed phase is on or past the boundary (a few ulps at most): at that
  // time at() already gives the slice beyond, and the next call looks for the boundary after it.
  // Without this the phase of the returned time can round to just short of the boundary, and every
  // later call returns that same boundary again (dopri5 would crawl by one ulp per step).
  double time = motion.t0 + (target - motion.phase0) / f;
  for (int i = 0;
       i < 64 && (f > 0.0 ? motion.phaseAt(time) < target : motion.phaseAt(time) > target); ++i) {
    time = std::nextafter(time, std::numeric_limits<double>::infinity());
  }
  return time > t ? time : std::nextafter(t, std::numeric_limits<double>::infinity());
}

}  // namespace drivetrain_stiffness

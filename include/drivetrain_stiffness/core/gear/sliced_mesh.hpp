// The mesh stiffness sliced in the mesh phase, and the rig's excitation along a measured motion:
// docs/model.md "Following the rig's motion".
#pragma once

#include <complex>
#include <memory>
#include <vector>

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

class SlicedMesh {
 public:
  /// 4 to 65536 uniform slices per mesh period, split further at the switching phases; each holds
  /// the phase table's mean k1 and k_c over it.
  SlicedMesh(std::shared_ptr<const AntiBacklashMesh> mesh, int slices);
  /// One slice holding the period means of k1 and k_c (the `linear_modal` fidelity).
  static std::shared_ptr<const SlicedMesh> periodMean(std::shared_ptr<const AntiBacklashMesh> mesh);

  int size() const { return static_cast<int>(k1_.size()); }
  double start(int j) const { return bounds_[j]; }    ///< [0, 1)
  double end(int j) const { return bounds_[j + 1]; }  ///< (0, 1]
  double k1(int j) const { return k1_[j]; }           ///< [N/m]
  double kChain(int j) const { return kc_[j]; }       ///< [N/m]
  /// e^{i 2 pi b_k} for boundary k in [0, size()] (exactly 1 at both ends).
  std::complex<double> boundaryPhasor(int k) const { return phasors_[k]; }
  /// The slice holding phase p in [0, 1): start <= p < end, or with `backward` start < p <= end.
  int sliceAt(double p, bool backward) const;
  const AntiBacklashMesh& mesh() const { return *mesh_; }
  /// Both flanks modelled (AntiBacklashMesh::antiBacklash).
  bool antiBacklash() const { return anti_backlash_; }

 private:
  SlicedMesh() = default;
  std::shared_ptr<const AntiBacklashMesh> mesh_;
  std::vector<double> bounds_, k1_, kc_;
  std::vector<std::complex<double>> phasors_;
  bool anti_backlash_ = false;
};

/// The sliced stiffness along a measured motion; immutable. A GearRotorModel on it supplies the
/// motion and the torque as inputs.
class SlicedExcitation : public GearExcitation {
 public:
  /// te_amplitude [m] of e = A sin(2 pi phi); backlash [m]; drive force = torque_gain T + load_term
  /// [N].
  SlicedExcitation(std::shared_ptr<const SlicedMesh> slices, double te_amplitude, double backlash,
                   double torque_gain, double load_term, const MeshMotion& motion = MeshMotion(),
                   double torque = 0.0);
  void at(double t, MeshInstant& out) const override { at(t, motion_, torque_, out); }
  /// The next slice boundary [s] the motion crosses after t; +inf when standing.
  double nextSwitch(double t) const override { return nextSwitch(t, motion_); }
  /// The same along `motion` at pinion torque `torque` [N·m] (a model's inputs).
  void at(double t, const MeshMotion& motion, double torque, MeshInstant& out) const;
  double nextSwitch(double t, const MeshMotion& motion) const;
  const MeshMotion& motion() const { return motion_; }
  double torque() const { return torque_; }  ///< [N·m]
  const SlicedMesh& slices() const { return *slices_; }

 private:
  std::shared_ptr<const SlicedMesh> slices_;
  double te_amplitude_, backlash_, torque_gain_, load_term_;
  MeshMotion motion_;
  double torque_;
};

}  // namespace drivetrain_stiffness

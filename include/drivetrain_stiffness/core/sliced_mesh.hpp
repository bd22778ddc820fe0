// The mesh stiffness sliced in the mesh phase, and the rig's excitation at a measured motion.
//
// At a fixed speed the mesh stiffness is periodic in time and PeriodicExponentialPropagator
// tabulates its propagators per output interval. A rig that runs up, steps its speed or reverses
// has no fixed period, so what is tabulated must not depend on the speed: the mesh phase domain.
// SlicedMesh splits one mesh period into slices (uniform, plus every tooth-count switch of both
// flanks, so the single/double-pair steps stay exact) and holds each slice's mean drive-flank
// stiffness k1 and back-path stiffness k_c (the mean of the phase table over the slice). Inside a
// slice the model is then linear time-invariant at any speed, and its propagator over any duration
// follows from one eigen-decomposition per slice (SlicedModalPropagator, docs/model.md "Following
// the rig's motion"). The slicing is the model's only approximation: a piecewise-constant stiffness
// whose error against the phase table falls as 1/slices^2 (midpoint rule; measured in
// docs/model.md).
//
// SlicedExcitation drives GearRotorModel with that stiffness along a measured motion (MeshMotion):
// the mesh phase phi(t) = phi_0 + f (t - t_0) [turns] at a signed mesh frequency f [Hz] (0:
// standing, < 0: reversed), re-anchored by the model's owner at each encoder reading. It is the
// reference the exact propagation is tested against (dopri5 on the same model) and the model of the
// dopri5 fallback.
#pragma once

#include <complex>
#include <memory>
#include <vector>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

class SlicedMesh {
 public:
  /// `slices` uniform slices per mesh period (>= 4, <= 65536), split further at the switching
  /// phases.
  SlicedMesh(std::shared_ptr<const AntiBacklashMesh> mesh, int slices);
  /// One slice over the whole period holding the table's exact period means of k1 and k_c
  /// (AntiBacklashMesh::periodMeans, the one mean every user takes: meanMeshStiffness): the
  /// stiffness the `linear_modal` fidelity holds (no parametric excitation), along a measured
  /// motion as at the nominal speed.
  static std::shared_ptr<const SlicedMesh> periodMean(std::shared_ptr<const AntiBacklashMesh> mesh);

  int size() const { return static_cast<int>(k1_.size()); }
  double start(int j) const { return bounds_[j]; }    ///< phase in [0, 1)
  double end(int j) const { return bounds_[j + 1]; }  ///< phase in (0, 1]
  double k1(int j) const { return k1_[j]; }           ///< [N/m]
  double kChain(int j) const { return kc_[j]; }       ///< [N/m]
  /// e^{i 2 pi b_k} for boundary k in [0, size()] (b_0 = 0, b_size = 1: both exactly 1): the TE
  /// forcing's phasor where a step starts or ends on a boundary, tabulated so that crossing a slice
  /// costs no sine or cosine of its own.
  std::complex<double> boundaryPhasor(int k) const { return phasors_[k]; }
  /// Slice holding phase p in [0, 1): start <= p < end, or with `backward` start < p <= end (the
  /// slice a reversed motion is in just after crossing a boundary).
  int sliceAt(double p, bool backward) const;
  const AntiBacklashMesh& mesh() const { return *mesh_; }
  /// Both flanks modelled (k_c > 0 or F_p > 0): the mesh force is k_s delta + c delta', F_p
  /// cancels.
  bool antiBacklash() const { return anti_backlash_; }

 private:
  SlicedMesh() = default;
  std::shared_ptr<const AntiBacklashMesh> mesh_;
  std::vector<double> bounds_, k1_, kc_;
  std::vector<std::complex<double>> phasors_;
  bool anti_backlash_ = false;
};

/// Immutable once built, so every model over it sees the same excitation. Its own motion and torque
/// (the constructor's) serve where the excitation stands alone (a scene's piece between two
/// readings); a GearRotorModel built on it takes the motion and the torque as its inputs instead
/// (setMotionInput, setTorqueInput) and evaluates at(t, motion, torque, out).
class SlicedExcitation : public GearExcitation {
 public:
  /// te_amplitude [m] of e = A sin(2 pi phi) (the manufacturing TE at mesh frequency, as
  /// RigExcitation's); backlash [m] of an ordinary gear; drive force = torque_gain T + load_term
  /// [N].
  SlicedExcitation(std::shared_ptr<const SlicedMesh> slices, double te_amplitude, double backlash,
                   double torque_gain, double load_term, const MeshMotion& motion = MeshMotion(),
                   double torque = 0.0);
  void at(double t, MeshInstant& out) const override { at(t, motion_, torque_, out); }
  /// The next slice boundary the motion crosses after t; +inf when standing (f = 0).
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

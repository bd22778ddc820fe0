// The sliced model's modes: one eigen-decomposition per slice and regime, made on first use and
// kept for the last parameter sets (docs/model.md "Following the rig's motion"). A part of
// SlicedModalPropagator.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/core/dynamics/sliced_contact_rules.hpp"

namespace drivetrain_stiffness {
namespace sliced {

using CVector = Eigen::Matrix<Complex, 6, 1>;
using CMatrix = Eigen::Matrix<Complex, 6, 6>;

/// |z|^2, written out (std::norm of a complex calls hypot in libstdc++).
inline double norm2(Complex z) { return z.real() * z.real() + z.imag() * z.imag(); }

/// One slice's modes in one regime.
struct Slice {
  CMatrix v, v_inv;
  CVector lambda, force_dir, drive_dir;  ///< eigenvalues, V^-1 e_F, V^-1 e_v
  std::array<Complex, 6> deflection{};   ///< weight_k (1, -1, 1) . u_k per mode
  std::array<double, 6> weight{};        ///< y = sum_k weight_k Re(V_k eta_k)
  std::array<Complex, 3> upper{};        ///< eigenvalues with Im > 0: the next seeds
  double fastest = 0.0;                  ///< max |lambda| [1/s]
  bool ready = false, usable = false, has_upper = false;
};

/// The slices' modes for the parameters of now, with those of the last parameter sets kept.
class SliceTables {
 public:
  /// Parameter sets whose decompositions are kept.
  static constexpr int kKeptParameterSets = 6;
  /// Takes parameters p, mesh mass m_s [kg]: a kept set as it was, or the longest unused one
  /// emptied for them.
  void select(const GearRotorParameters& p, double m_s);
  /// Sizes regime r's slices of the active set to n.
  void sizeRegime(MeshRegime r, int n) { activeSlices(r).resize(static_cast<std::size_t>(n)); }
  /// The parameters of the active set.
  const GearRotorParameters& parameters() const { return p_; }
  /// Regime r's slice j, decomposed on first use with the rules' mesh terms.
  const Slice& slice(MeshRegime r, int j, const ContactRules& rules) const;
  /// Slices decomposed.
  long decompositions() const { return decompositions_; }
  /// Of those, by Eigen's general eigensolver.
  long generalDecompositions() const { return general_decompositions_; }
  /// select calls that took a kept set back.
  long keptSetsReused() const { return kept_sets_reused_; }

 private:
  /// What a decomposition reads of the parameters: a kept set is taken back where all are equal.
  struct DecompositionKey {
    std::array<double, 2> bearing_stiffness{}, bearing_damping{};
    double mesh_damping = 0.0, pinion_mass = 0.0, gear_mass = 0.0, mesh_mass = 0.0;
    bool operator==(const DecompositionKey& o) const {
      return bearing_stiffness == o.bearing_stiffness && bearing_damping == o.bearing_damping &&
             mesh_damping == o.mesh_damping && pinion_mass == o.pinion_mass &&
             gear_mass == o.gear_mass && mesh_mass == o.mesh_mass;
    }
  };
  /// One parameter set's slices, per MeshRegime, per slice.
  struct KeptSet {
    DecompositionKey key;
    long last_used = 0;
    std::array<std::vector<Slice>, kRegimes> slices;
  };
  std::vector<Slice>& activeSlices(MeshRegime r) const {
    return sets_[active_].slices[static_cast<std::size_t>(r)];
  }
  /// Slice j's modes by Newton from three seeds; false where not verified.
  bool decomposeSeeded(MeshRegime r, int j, Slice& s, std::array<Complex, 3> seeds,
                       const ContactRules& rules) const;
  /// Slice j's modes by Eigen's EigenSolver.
  void decomposeGeneral(MeshRegime r, int j, Slice& s, const ContactRules& rules) const;
  /// The first-order system matrix of regime r in slice j.
  Matrix6 systemMatrix(MeshRegime r, int j, const ContactRules& rules) const;

  GearRotorParameters p_;
  double m_s_ = 0.0;
  mutable std::array<KeptSet, kKeptParameterSets> sets_;
  std::size_t active_ = 0;
  int previous_ = -1;  ///< the set before the last change, -1: none
  long use_clock_ = 0, kept_sets_reused_ = 0;
  mutable long decompositions_ = 0, general_decompositions_ = 0;
};

}  // namespace sliced
}  // namespace drivetrain_stiffness

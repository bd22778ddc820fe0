// The sliced model's contact rules: each flank's linear states, the mesh regimes they make, and
// the conditions that tell which regime a state is in (docs/model.md "Following the rig's
// motion"). A part of SlicedModalPropagator.
#pragma once

#include <array>
#include <complex>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"
#include "drivetrain_stiffness/core/gear/sliced_mesh.hpp"

namespace drivetrain_stiffness {
namespace sliced {

using Complex = std::complex<double>;

/// One flank's contact (the Modelica ElastoBacklash rule): each state is linear.
enum class FlankState { kUnloaded = 0, kLoaded = 1, kStiffened = 2 };
/// The drive flank's and the back path's states, index 3 drive + back.
enum class MeshRegime {
  kNoContact = 0,
  kBackFlank = 1,
  kBackStiffened = 2,
  kDriveFlank = 3,
  kBothFlanks = 4,
  kDriveLoadedBackStiffened = 5,
  kDriveStiffened = 6,
  kDriveStiffenedBackLoaded = 7,
  kBothStiffened = 8
};
inline constexpr int kRegimes = 9;
/// The regime of the two flanks' states.
inline MeshRegime regimeOf(FlankState drive, FlankState back) {
  return static_cast<MeshRegime>(3 * static_cast<int>(drive) + static_cast<int>(back));
}
/// The drive flank's state in regime r.
inline FlankState driveState(MeshRegime r) {
  return static_cast<FlankState>(static_cast<int>(r) / 3);
}
/// The back path's state in regime r.
inline FlankState backState(MeshRegime r) {
  return static_cast<FlankState>(static_cast<int>(r) % 3);
}

/// Mesh force = stiffness delta + damping delta' + constant.
struct MeshTerms {
  double stiffness, damping, constant;
};
/// Spring force c0 + alpha delta, plus damper beta delta'; `exists` false without stiffness.
struct FlankLaw {
  double c0, alpha, beta;
  bool exists;
};
/// c0 + alpha delta + beta delta' > 0 (strict) or >= 0, with regimeMargin's scales.
struct ContactCondition {
  double c0, alpha, beta, abs_alpha, abs_beta, inverse_scale;
  bool strict;
};
/// `first` holds, or (either) `first` or `second`.
struct Clause {
  ContactCondition first{}, second{};
  bool either = false;
};
/// Regime r's rules in slice j; `possible` false where it has no stiffness there.
struct RegimeConditions {
  std::array<Clause, 6> c{};
  int n = 0;
  bool possible = true;
  MeshTerms terms{0.0, 0.0, 0.0};
};

/// The contact rules over a sliced mesh for one mesh damping, tabulated per regime and slice.
class ContactRules {
 public:
  /// te_amplitude [m], backlash [m]. Throws InvalidInput (no slices, a negative value).
  ContactRules(std::shared_ptr<const SlicedMesh> slices, double te_amplitude, double backlash);
  /// Takes mesh damping c [N·s/m]; the tables are remade where it changed.
  void setMeshDamping(double c);

  /// The sliced mesh the rules are for.
  const SlicedMesh& slices() const { return *slices_; }
  /// TE amplitude [m].
  double teAmplitude() const { return te_amplitude_; }
  /// Every contact of the mesh loaded.
  MeshRegime loadedRegime() const {
    return slices_->antiBacklash() ? MeshRegime::kBothFlanks : MeshRegime::kDriveFlank;
  }
  /// Flank 0 (drive) or 1 (back path) in slice j.
  FlankLaw flankLaw(int flank, int j) const;
  /// The mesh force's terms in regime r, slice j.
  MeshTerms meshTerms(MeshRegime r, int j) const;
  /// Regime r's rules in slice j, tabulated when r is first met.
  const RegimeConditions& conditions(MeshRegime r, int j) const {
    std::vector<RegimeConditions>& table = conditions_[static_cast<std::size_t>(r)];
    if (table.empty()) tabulateRegimeConditions(r);
    return table[static_cast<std::size_t>(j)];
  }
  /// >= 0 in regime r: the least rule's force over its scale.
  double regimeValue(MeshRegime r, int j, const State6& y, Complex e_theta, double w) const;
  /// The contacts at y are those of regime r, given e^{i theta}.
  bool inRegime(MeshRegime r, int j, const State6& y, Complex e_theta, double w) const;
  /// The linear regime y is in, if any.
  std::optional<MeshRegime> regimeAt(int j, const State6& y, Complex e_theta, double w) const;

 private:
  double driveFlankDamping(int j) const;
  RegimeConditions makeConditions(MeshRegime r, int j) const;
  void tabulateRegimeConditions(MeshRegime r) const;

  std::shared_ptr<const SlicedMesh> slices_;
  double te_amplitude_, backlash_, mesh_damping_ = 0.0;
  mutable std::array<std::vector<RegimeConditions>, kRegimes> conditions_;
  /// The mesh damping conditions_ was made with (NaN: not yet).
  double conditions_mesh_damping_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace sliced
}  // namespace drivetrain_stiffness

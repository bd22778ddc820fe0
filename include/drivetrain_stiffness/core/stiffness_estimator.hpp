// The online bearing-stiffness estimator, free of ROS: it holds one BearingSupport per rig
// support, takes the measured pinion torque and the preload settings as plain values, and returns
// the updated stiffness. Updates are transactional: an input that fails validation (InvalidInput)
// or has no admissible equilibrium (UnreachableLoad) throws and leaves the previous state intact,
// so one bad sample can never poison later estimates. Each support is warm-started from its last
// solution. No clock is read: the caller stamps the results.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// Operating settings of one support as carried by the preload input (SI units).
struct PreloadSetting {
  std::string name;
  double axial_preload = 0.0;       ///< [N]
  double radial_preload = 0.0;      ///< [N]
  double inner_interference = 0.0;  ///< diametral [m]
  double outer_interference = 0.0;  ///< diametral [m]
};

/// Input plausibility limits; anything beyond is rejected as absurd.
struct EstimatorLimits {
  double max_abs_torque = 100.0;   ///< [N·m]
  double max_preload = 1e5;        ///< [N]
  double max_interference = 1e-3;  ///< [m]
  /// [-] A support is re-solved only when its radial load moved by more than this fraction of its
  /// total load (radial + axial preload) since its last solve; 0 = every update. Ball-contact
  /// stiffness grows as Q^(1/3) (Hertz), so the stiffness lags the exact one by about tol / 3.
  double load_tolerance = 0.0;
  /// The limits' own rules, in one place for the estimator and the pipeline's options: each bound
  /// > 0, and the load tolerance by requireLoadTolerance (below) under `load_tolerance_field`, the
  /// name the caller's user knows (load_tolerance, ~bearing_load_tolerance). InvalidInput naming
  /// the field otherwise.
  void validate(std::string_view load_tolerance_field = "load_tolerance") const;
};

/// The bound of EstimatorLimits::load_tolerance, one rule for StiffnessEstimator and the pipeline's
/// options (~bearing_load_tolerance): 0 <= tol <= 0.1 (past 10 % of the load the stiffness would
/// lag the exact one by more than ~3 %, tol / 3 by Hertz).
constexpr double kMaxLoadTolerance = 0.1;
/// Throws InvalidInput("<field> = <value>: ...") outside [0, kMaxLoadTolerance] (NaN included);
/// `field` is the name the caller's user knows (load_tolerance, bearing_load_tolerance).
void requireLoadTolerance(std::string_view field, double value);

struct SupportEstimate {
  std::string name;
  double radial_load = 0.0;  ///< radial preload + share of |mesh force| [N]
  double axial_load = 0.0;   ///< axial preload (single) or 0 (pair) [N]
  /// The Hertz model's solution, its tangent `stiffness` multiplied by the support's
  /// stiffness_scale; `displacement` is the unscaled model's (the next solve's warm start): the
  /// support's deflection is displacement / stiffness_scale.
  BearingSolution solution;
};

struct MeshEstimate {
  double phase = 0.0;     ///< mesh phase in [0, 1)
  CompositeMesh current;  ///< k1, k2, k_chain, composite and flank state at this phase and load
  double mean = 0.0;  ///< composite stiffness averaged over a mesh period, same flank state [N/m]
};

struct StiffnessEstimate {
  double torque = 0.0;      ///< pinion input torque [N·m]
  double mesh_force = 0.0;  ///< |T| / r_b,pinion [N]
  std::vector<SupportEstimate> supports;
  MeshEstimate mesh;
};

class StiffnessEstimator {
 public:
  /// Validates the rig and limits and solves the initial state (torque 0, preloads from the
  /// config). The rig is read only, and shared: the pipeline hands the same one to the dynamics and
  /// the calibration (the preloads that change at run time are this estimator's state, not the
  /// rig's).
  explicit StiffnessEstimator(std::shared_ptr<const RigConfig> rig,
                              const EstimatorLimits& limits = {});
  /// The same on a copy of `rig`.
  StiffnessEstimator(const RigConfig& rig, const EstimatorLimits& limits = {});

  /// New pinion torque [N·m] at pinion angle [rad]; the mesh force F = |T| / r_b (seed 000 eq 14)
  /// loads every support radially in proportion to its mesh_load_share, on top of its radial
  /// preload, and with its sign sets the anti-backlash flank state.
  const StiffnessEstimate& setTorque(double torque, double pinion_angle = 0.0);
  /// New settings for the named supports (others keep theirs). Unknown names are an error. In
  /// place, as setTorque: no heap allocation once every support has been solved once.
  const StiffnessEstimate& setPreloads(const std::vector<PreloadSetting>& settings);
  /// The value checks of setTorque / setPreloads alone (InvalidInput naming the field), without
  /// solving: lets a caller refuse bad data before acting on its time stamp.
  void validateTorque(double torque) const;
  void validatePreloads(const std::vector<PreloadSetting>& settings) const;
  /// Back to the configured preloads and zero torque (e.g. after a time jump).
  const StiffnessEstimate& reset();

  const StiffnessEstimate& current() const { return estimate_; }
  /// Current radial stiffness per shaft (pinion, gear) [N/m]: the supports of each shaft in
  /// parallel, as the 3-DOF model's k_r1, k_r2 (seed 000 eq 15).
  std::array<double, 2> shaftRadialStiffness() const;
  const RigConfig& rig() const { return *rig_; }
  std::shared_ptr<const RigConfig> sharedRig() const { return rig_; }
  /// Support i's configuration with its current preload settings, and its Hertz model.
  const BearingSupportConfig& supportConfig(std::size_t i) const { return supports_.at(i).config; }
  const BearingSupport& supportModel(std::size_t i) const { return *supports_.at(i).model; }
  /// Changes whenever a support's settings or model may have changed (reset, setPreloads), never
  /// with the torque, and is unique across every estimator of the process: a cache of results that
  /// depend on supportConfig / supportModel alone (StaticTeModel::shaftDeflection) is valid while
  /// it stays the same.
  long supportsRevision() const { return supports_revision_; }
  const AntiBacklashMesh& mesh() const { return *mesh_; }
  /// The same read-only table, for the dynamics of the same rig (built once, shared).
  std::shared_ptr<const AntiBacklashMesh> sharedMesh() const { return mesh_; }

 private:
  struct Support {
    BearingSupportConfig config;
    std::unique_ptr<BearingSupport> model;
    /// setPreloads' scratch: new geometry is assigned into it (no allocation), and it is swapped
    /// with `model` once every support has solved.
    std::unique_ptr<BearingSupport> spare;
  };
  /// Solves all `supports` (new models: cold starts) for `torque`; throws without touching the
  /// state.
  StiffnessEstimate solveAll(double torque, double pinion_angle,
                             const std::vector<Support>& supports) const;
  MeshEstimate meshAt(double signed_mesh_force, double pinion_angle) const;
  /// Radial load of a support: its radial preload plus its share of the mesh force [N].
  static double radialLoad(const BearingSupportConfig& c, double mesh_force);
  /// The ~load_tolerance shortcut: support i's last solution still stands for `radial_load`, its
  /// model and radial preload unchanged (the caller's part), the load within the tolerance.
  bool solutionStands(std::size_t i, double radial_load) const;
  /// Index of the support named `name`, or supports_.size().
  std::size_t supportIndex(const std::string& name) const;
  static std::unique_ptr<BearingSupport> build(const BearingSupportConfig& c);

  std::shared_ptr<const RigConfig> rig_;
  EstimatorLimits limits_;
  std::shared_ptr<const AntiBacklashMesh> mesh_;
  std::array<double, 3>
      mean_k1_kchain_{};  ///< period means of k1, k_chain (for the flank state) and k1 + k_chain
  std::vector<Support> supports_;
  StiffnessEstimate estimate_;
  /// setTorque's and setPreloads' per-support scratch (one per support, sized with supports_): a
  /// new solution and the load it is for, swapped into estimate_ once every support has solved;
  /// setPreloads stages the new settings here too.
  struct Workspace {
    BearingSolution solution;
    double radial_load = 0.0;
    bool solved = false;
    double axial_preload = 0.0, radial_preload = 0.0;
    Interference interference;
    bool rebuilt = false;  ///< the spare model holds the new geometry
  };
  std::vector<Workspace> workspace_;
  double last_pinion_angle_ = 0.0;
  long supports_revision_ = 0;
  /// The next supports_revision_ (process-wide, so two estimators never share one).
  static long nextSupportsRevision();
};

}  // namespace drivetrain_stiffness

// The online bearing and mesh stiffness estimator, free of ROS and clocks. Every update is
// transactional: an input that throws leaves the previous state intact.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// One support's settings as the preload input carries them.
struct PreloadSetting {
  std::string name;
  double axial_preload = 0.0;       ///< [N]
  double radial_preload = 0.0;      ///< [N]
  double inner_interference = 0.0;  ///< [m] diametral
  double outer_interference = 0.0;  ///< [m] diametral
};

/// Input plausibility limits.
struct EstimatorLimits {
  double max_abs_torque = 100.0;   ///< [N·m]
  double max_preload = 1e5;        ///< [N]
  double max_interference = 1e-3;  ///< [m]
  /// [-] re-solve a support when its radial load moved by more than this fraction of its total
  /// load; 0: every update (docs/ros_api.md ~bearing_load_tolerance).
  double load_tolerance = 0.0;
  /// Throws InvalidInput naming the field unless each bound is > 0 and the load tolerance (named
  /// `load_tolerance_field`) passes requireLoadTolerance.
  void validate(std::string_view load_tolerance_field = "load_tolerance") const;
};

/// The largest load tolerance: the stiffness lags the exact one by about tol / 3 (Hertz).
constexpr double kMaxLoadTolerance = 0.1;
/// Throws InvalidInput naming `field` outside [0, kMaxLoadTolerance] or NaN.
void requireLoadTolerance(std::string_view field, double value);

struct SupportEstimate {
  std::string name;
  double radial_load = 0.0;  ///< [N] radial preload + share of |mesh force|
  double axial_load = 0.0;   ///< [N] axial preload (single) or 0 (pair)
  /// The Hertz solution: `stiffness` scaled by stiffness_scale, `displacement` unscaled.
  BearingSolution solution;
};

struct MeshEstimate {
  double phase = 0.0;     ///< [0, 1)
  CompositeMesh current;  ///< at this phase and load
  double mean = 0.0;      ///< [N/m] period mean, same flank state
};

struct StiffnessEstimate {
  double torque = 0.0;      ///< [N·m] pinion
  double mesh_force = 0.0;  ///< [N] |T| / r_b,pinion
  std::vector<SupportEstimate> supports;
  MeshEstimate mesh;
};

class StiffnessEstimator {
 public:
  /// Solves torque 0 at the configured preloads. Throws InvalidInput for an invalid rig or limits.
  explicit StiffnessEstimator(std::shared_ptr<const RigConfig> rig,
                              const EstimatorLimits& limits = {});
  /// The same on a copy of `rig`.
  StiffnessEstimator(const RigConfig& rig, const EstimatorLimits& limits = {});

  /// New pinion torque [N·m] at pinion angle [rad]: F = |T| / r_b (seed 000 eq 14) loads each
  /// support by its mesh_load_share. Throws InvalidInput or UnreachableLoad.
  const StiffnessEstimate& setTorque(double torque, double pinion_angle = 0.0);
  /// New settings for the named supports. Throws InvalidInput (an unknown name included) or
  /// UnreachableLoad. Allocation-free once every support has been solved.
  const StiffnessEstimate& setPreloads(const std::vector<PreloadSetting>& settings);
  /// setTorque's and setPreloads' value checks alone: InvalidInput naming the field.
  void validateTorque(double torque) const;
  void validatePreloads(const std::vector<PreloadSetting>& settings) const;
  /// Back to the configured preloads and zero torque.
  const StiffnessEstimate& reset();

  const StiffnessEstimate& current() const { return estimate_; }
  /// [N/m] per shaft, its supports in parallel: k_r1, k_r2 (seed 000 eq 15).
  std::array<double, 2> shaftRadialStiffness() const;
  const RigConfig& rig() const { return *rig_; }
  std::shared_ptr<const RigConfig> sharedRig() const { return rig_; }
  /// Support i's configuration at its current settings, and its model.
  const BearingSupportConfig& supportConfig(std::size_t i) const { return supports_.at(i).config; }
  const BearingSupport& supportModel(std::size_t i) const { return *supports_.at(i).model; }
  /// Changes, uniquely within the process, whenever a support's settings or model may have.
  long supportsRevision() const { return supports_revision_; }
  const AntiBacklashMesh& mesh() const { return *mesh_; }
  /// The same table, shared.
  std::shared_ptr<const AntiBacklashMesh> sharedMesh() const { return mesh_; }

 private:
  struct Support {
    BearingSupportConfig config;
    std::unique_ptr<BearingSupport> model;
    /// setPreloads' scratch, swapped with `model` once every support has solved.
    std::unique_ptr<BearingSupport> spare;
  };
  /// Solves all `supports` cold for `torque`; throws without touching the state.
  StiffnessEstimate solveAll(double torque, double pinion_angle,
                             const std::vector<Support>& supports) const;
  MeshEstimate meshAt(double signed_mesh_force, double pinion_angle) const;
  /// [N] radial preload plus the share of the mesh force.
  static double radialLoad(const BearingSupportConfig& c, double mesh_force);
  /// Support i's last solution stands for `radial_load` [N] within the load tolerance.
  bool solutionStands(std::size_t i, double radial_load) const;
  /// Index of the support named `name`, or supports_.size().
  std::size_t supportIndex(const std::string& name) const;
  static std::unique_ptr<BearingSupport> build(const BearingSupportConfig& c);

  std::shared_ptr<const RigConfig> rig_;
  EstimatorLimits limits_;
  std::shared_ptr<const AntiBacklashMesh> mesh_;
  std::array<double, 3> mean_k1_kchain_{};  ///< period means of k1, k_chain and k1 + k_chain
  std::vector<Support> supports_;
  StiffnessEstimate estimate_;
  /// setPreloads' steps: the settings staged in workspace_ (a changed geometry rebuilt into the
  /// spare; throws InvalidInput or UnreachableLoad naming the support), each support solved there
  /// at mesh force [N] (throws UnreachableLoad), then everything swapped in.
  void stagePreloads(const std::vector<PreloadSetting>& settings);
  void solveStaged(double mesh_force);
  void commitStaged();
  /// Per-support scratch, swapped into estimate_ once every support has solved.
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
  /// The next supports_revision_, process-wide.
  static long nextSupportsRevision();
};

}  // namespace drivetrain_stiffness

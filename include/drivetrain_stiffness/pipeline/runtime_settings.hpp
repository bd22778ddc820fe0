// The settings a user may change while the estimator runs: docs/ros_api.md "dynamic_reconfigure".
#pragma once

#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// The range of the display scale of displacements (tf, markers).
constexpr double kMinExaggeration = 1.0;
constexpr double kMaxExaggeration = 1e8;
/// Throws InvalidInput naming exaggeration outside [kMinExaggeration, kMaxExaggeration] or NaN.
void requireExaggeration(double exaggeration);

struct RuntimeSettings {
  double mesh_damping_ratio = 0.05;     ///< [-] in [0, 1]
  double bearing_damping_ratio = 0.02;  ///< [-] in [0, 1]
  Fidelity fidelity = Fidelity::kFull;
  double stiffness_rate = 0.0;  ///< [Hz] in [0, 1e5]; 0 = every input
  double exaggeration = 2e4;    ///< [-] in [1, 1e8]
  double tf_rate = 30.0;        ///< [Hz] in [0, 1000]; 0 = none

  /// Throws InvalidInput naming the first field outside its range (NaN included).
  void validate() const;
  /// The defaults with the gearbox's damping ratios.
  static RuntimeSettings forRig(const RigConfig& rig);
};

}  // namespace drivetrain_stiffness

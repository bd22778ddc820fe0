// The settings a user may change while the estimator runs (dynamic_reconfigure, cfg/Estimator.cfg):
// one value, validated in one place with the .cfg's ranges and applied whole, whether it comes from
// the start-up parameters (node, nodelet, drivetrain_replay --params) or from a reconfiguration.
// The pipeline uses the damping, the fidelity and the stiffness rate; the message sink the display
// scale and the tf rate. ROS-free.
#pragma once

#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

/// The display scale of displacements (tf, markers), one rule for the settings and RigVisualizer:
/// at least 1 (a display never shrinks the model's motion), at most 1e8 (micrometres become
/// 100 m, past anything a gear-scale display can show).
constexpr double kMinExaggeration = 1.0;
constexpr double kMaxExaggeration = 1e8;
/// Throws InvalidInput("exaggeration = <value>: ...") outside [kMinExaggeration, kMaxExaggeration]
/// (NaN included).
void requireExaggeration(double exaggeration);

struct RuntimeSettings {
  double mesh_damping_ratio = 0.05;  ///< [-] in [0, 1] (requireDampingRatio, core/rig_model.hpp),
                                     ///< of the torsional mesh mode
  double bearing_damping_ratio = 0.02;  ///< [-] in [0, 1], of each shaft on its bearings
  Fidelity fidelity = Fidelity::kFull;
  double stiffness_rate =
      0.0;  ///< [Hz] in [0, 1e5]: largest stiffness rate on stamps; 0 = every input
  double exaggeration = 2e4;  ///< [-] in [1, 1e8] (requireExaggeration): display scale of
                              ///< displacements in tf and markers
  double tf_rate = 30.0;      ///< [Hz] in [0, 1000]: tf and markers on sample time; 0 = none

  /// Throws InvalidInput naming the first field outside its range (NaN included).
  void validate() const;
  /// The defaults with the gearbox's damping ratios (its dynamics block, if it has one).
  static RuntimeSettings forRig(const RigConfig& rig);
};

}  // namespace drivetrain_stiffness

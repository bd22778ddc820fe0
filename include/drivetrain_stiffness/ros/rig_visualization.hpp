// What rviz shows of the rig: tf2 frames for the pinion and the gear and markers (gear bodies,
// the mesh force arrow, a text with the current resonances). Positions and angles come from the
// model; displacements and the torsional deflection are scaled by `exaggeration` (micrometres
// would be invisible at gear scale). Shared by the node and the replay tool.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <visualization_msgs/MarkerArray.h>

#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace drivetrain_stiffness {

struct VisualizationFrames {
  std::string rig = "rig";        ///< fixed frame: pinion centre at the origin, gear centre on +x
  std::string pinion = "pinion";  ///< rotates with the pinion, displaced along the line of action
  std::string gear = "gear";
};

class RigVisualizer {
 public:
  /// exaggeration in [1, 1e8] (requireExaggeration, the settings' rule) scales the model's
  /// displacements for display (InvalidInput otherwise).
  RigVisualizer(const SpurGearGeometry& geometry, double face_width, double nominal_mesh_force,
                const VisualizationFrames& frames, double exaggeration);
  void setExaggeration(double exaggeration);
  double exaggeration() const { return exaggeration_; }

  /// rig -> pinion and rig -> gear at sample.t; pinion_angle is the nominal pinion angle [rad].
  std::vector<geometry_msgs::TransformStamped> transforms(const ros::Time& stamp,
                                                          const DynamicsSample& sample,
                                                          double pinion_angle) const;
  /// `resonance`: the current estimate, shown as text (null: none yet).
  visualization_msgs::MarkerArray markers(const ros::Time& stamp, const DynamicsSample& sample,
                                          const ResonanceEstimate* resonance) const;
  /// Unit vector of the line of action in the rig frame (the sense of positive x_p, x_g).
  std::array<double, 2> lineOfAction() const { return {sin_aw_, -cos_aw_}; }

 private:
  double r_tip_[2], r_pitch_[2], r_base_[2], center_distance_, sin_aw_, cos_aw_, face_width_;
  double ratio_;        ///< z_p / z_g
  double arrow_scale_;  ///< [m/N] arrow length per newton of mesh force
  VisualizationFrames frames_;
  double exaggeration_ = 1.0;
};

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/ros/rig_visualization.hpp"

#include <cmath>
#include <cstdio>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

geometry_msgs::Quaternion aboutZ(double angle) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(0.5 * angle);
  q.w = std::cos(0.5 * angle);
  return q;
}

visualization_msgs::Marker marker(const std::string& frame, const ros::Time& stamp,
                                  const std::string& ns, int id, int type) {
  visualization_msgs::Marker m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;  // normalised (rviz warns about an all-zero quaternion)
  m.frame_locked = true;
  m.color.a = 1.0;
  return m;
}

}  // namespace

RigVisualizer::RigVisualizer(const SpurGearGeometry& g, double face_width,
                             double nominal_mesh_force, const VisualizationFrames& frames,
                             double exaggeration)
    : frames_(frames) {
  for (int i = 0; i < 2; ++i) {
    r_tip_[i] = g.tipRadius(i);
    r_pitch_[i] = g.operatingPitchRadius(i);
    r_base_[i] = g.baseRadius(i);
  }
  center_distance_ = g.centerDistance();
  // The line of action is the internal common tangent of the base circles through the pitch point
  // (r_w1, 0); from the pinion's tangency point T1 = r_b1 (cos a_w, sin a_w) towards T2 its
  // direction is (sin a_w, -cos a_w) (from a_w = (r_b1 + r_b2) / cos a_w).
  sin_aw_ = std::sin(g.operatingPressureAngle());
  cos_aw_ = std::cos(g.operatingPressureAngle());
  face_width_ = face_width;
  ratio_ = r_base_[0] / r_base_[1];
  // The nominal mesh force draws an arrow as long as the pinion's pitch radius.
  arrow_scale_ = r_pitch_[0] / std::max(std::abs(nominal_mesh_force), 1e-3);
  setExaggeration(exaggeration);
}

void RigVisualizer::setExaggeration(double exaggeration) {
  requireExaggeration(exaggeration);  // the settings' rule (runtime_settings.hpp)
  exaggeration_ = exaggeration;
}

std::vector<geometry_msgs::TransformStamped> RigVisualizer::transforms(const ros::Time& stamp,
                                                                       const DynamicsSample& s,
                                                                       double pinion_angle) const {
  std::vector<geometry_msgs::TransformStamped> out(2);
  // Pinion: transverse displacement x_p along the line of action; nominal rotation.
  out[0].header.stamp = stamp;
  out[0].header.frame_id = frames_.rig;
  out[0].child_frame_id = frames_.pinion;
  out[0].transform.translation.x = exaggeration_ * s.state[0] * sin_aw_;
  out[0].transform.translation.y = -exaggeration_ * s.state[0] * cos_aw_;
  out[0].transform.rotation = aboutZ(pinion_angle);
  // Gear: at the centre distance, displaced by x_g; turns the other way at z_p / z_g (= r_b1 /
  // r_b2) and lags by the torsional deflection x = r_b1 theta_p - r_b2 theta_g (seed 000 eq 12).
  out[1].header.stamp = stamp;
  out[1].header.frame_id = frames_.rig;
  out[1].child_frame_id = frames_.gear;
  out[1].transform.translation.x = center_distance_ + exaggeration_ * s.state[1] * sin_aw_;
  out[1].transform.translation.y = -exaggeration_ * s.state[1] * cos_aw_;
  out[1].transform.rotation =
      aboutZ(-ratio_ * pinion_angle + exaggeration_ * s.state[2] / r_base_[1]);
  return out;
}

visualization_msgs::MarkerArray RigVisualizer::markers(const ros::Time& stamp,
                                                       const DynamicsSample& s,
                                                       const ResonanceEstimate* resonance) const {
  visualization_msgs::MarkerArray out;
  const std::string* frames[2] = {&frames_.pinion, &frames_.gear};
  const float colours[2][3] = {{0.2f, 0.45f, 0.85f}, {0.6f, 0.6f, 0.62f}};
  for (int i = 0; i < 2; ++i) {
    // Body: a disc of tip diameter and face width.
    visualization_msgs::Marker body =
        marker(*frames[i], stamp, "gear_bodies", i, visualization_msgs::Marker::CYLINDER);
    body.scale.x = body.scale.y = 2.0 * r_tip_[i];
    body.scale.z = face_width_;
    body.color.r = colours[i][0], body.color.g = colours[i][1], body.color.b = colours[i][2];
    body.color.a = 0.8f;
    out.markers.push_back(body);
    // A mark on the rim, so the rotation is visible.
    visualization_msgs::Marker mark =
        marker(*frames[i], stamp, "rotation_marks", i, visualization_msgs::Marker::CUBE);
    mark.pose.position.x = 0.8 * r_tip_[i];
    mark.pose.position.z = 0.5 * face_width_;
    mark.scale.x = 0.3 * r_tip_[i];
    mark.scale.y = 0.12 * r_tip_[i];
    mark.scale.z = 0.2 * face_width_;
    mark.color.r = 1.0f, mark.color.g = 0.8f, mark.color.b = 0.1f;
    out.markers.push_back(mark);
  }
  // Mesh force on the gear, at the pitch point, along the line of action.
  visualization_msgs::Marker arrow =
      marker(frames_.rig, stamp, "mesh_force", 0, visualization_msgs::Marker::ARROW);
  geometry_msgs::Point a, b;
  a.x = r_pitch_[0];
  a.z = face_width_;
  const double length = arrow_scale_ * s.mesh_force;
  b.x = a.x + length * sin_aw_;
  b.y = -length * cos_aw_;
  b.z = a.z;
  arrow.points = {a, b};
  arrow.scale.x = 0.06 * r_pitch_[0];  // shaft diameter
  arrow.scale.y = 0.12 * r_pitch_[0];  // head diameter
  arrow.scale.z = 0.2 * r_pitch_[0];   // head length
  arrow.color.r = 0.9f, arrow.color.g = 0.1f, arrow.color.b = 0.1f;
  out.markers.push_back(arrow);
  // The current resonance estimate as text above the mesh.
  visualization_msgs::Marker text =
      marker(frames_.rig, stamp, "resonance", 0, visualization_msgs::Marker::TEXT_VIEW_FACING);
  text.pose.position.x = 0.5 * center_distance_;
  text.pose.position.y = r_tip_[1] + 0.5 * r_pitch_[0];
  text.pose.position.z = face_width_;
  text.scale.z = 0.12 * r_pitch_[0];  // text height
  text.color.r = text.color.g = text.color.b = 1.0f;
  char line[160];
  std::snprintf(line, sizeof line, "F_mesh %.2f N  TE %.3g um (x%.0f)", s.mesh_force,
                1e6 * s.dynamic_te, exaggeration_);
  text.text = line;
  if (resonance) {
    for (const Mode& m : resonance->modes) {
      std::snprintf(line, sizeof line, "\n%.0f Hz (%s, zeta %.3f)", m.natural_frequency,
                    m.dominant.c_str(), m.damping_ratio);
      text.text += line;
    }
    if (resonance->floquet_valid) {
      std::snprintf(line, sizeof line, "\nFloquet margin %.3f", resonance->floquet_margin);
      text.text += line;
    }
  }
  out.markers.push_back(text);
  return out;
}

}  // namespace drivetrain_stiffness

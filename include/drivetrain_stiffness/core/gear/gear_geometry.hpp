// Involute spur gear pair geometry (ISO 21771:2007 notation), the path of contact and the mesh
// phase: docs/gear_model.md "1. Geometry and mesh phase". s runs along the line of action from T1.
#pragma once

#include <array>
#include <optional>

#include "drivetrain_stiffness/core/bearing/interference_fit.hpp"

namespace drivetrain_stiffness {

struct GearPairSpec {
  double module = 0.0;                              ///< m (normal) [m]
  double pressure_angle = 0.0;                      ///< alpha (normal) [rad]
  double helix_angle = 0.0;                         ///< beta [rad]; ISO 6336 only
  std::array<int, 2> teeth{{0, 0}};                 ///< z_pinion, z_gear
  std::array<double, 2> profile_shift{{0.0, 0.0}};  ///< x [-]
  double addendum_coefficient = 1.0;                ///< h_aP* (ISO 53)
  double tool_dedendum_coefficient = 1.25;          ///< h_fP* (ISO 53)
  double face_width = 0.0;                          ///< b [m]
  std::optional<double> center_distance;            ///< a_w [m]; default: tight mesh
  ElasticMaterial material{2.06e11, 0.3};           ///< both gears
  std::array<double, 2> bore_diameter{{0.0, 0.0}};  ///< [m] for the fillet foundation; 0: r_f/2
};

/// A contact point on the LOA.
struct ContactPoint {
  double s = 0.0;                                    ///< [m] from T1
  std::array<double, 2> radius{{0.0, 0.0}};          ///< r_c [m] on pinion, gear
  std::array<double, 2> pressure_angle{{0.0, 0.0}};  ///< alpha_c = acos(r_b / r_c) [rad]
};

class SpurGearGeometry {
 public:
  /// Throws InvalidInput naming the field for undercut, pointed tips, interference, a contact ratio
  /// below 1 or an unreachable centre distance.
  explicit SpurGearGeometry(const GearPairSpec& spec);

  const GearPairSpec& spec() const { return spec_; }
  double referenceRadius(int i) const { return r_[i]; }        ///< r = m z / 2
  double baseRadius(int i) const { return rb_[i]; }            ///< r_b = r cos(alpha)
  double tipRadius(int i) const { return ra_[i]; }             ///< r_a = r + m (h_a + x - k)
  double rootRadius(int i) const { return rf_[i]; }            ///< r_f = r - m (h_fP - x)
  double operatingPitchRadius(int i) const { return rw_[i]; }  ///< r_w = r_b / cos(alpha_w)
  double halfToothAngleAtBase(int i) const {
    return alpha2_[i];
  }  ///< alpha_2 = pi/(2z) + 2 x tan(alpha)/z + inv(alpha)
  double operatingToothThickness(int i) const {
    return sw_[i];
  }  ///< s_w, arc on the operating pitch circle
  double tipShortening() const { return tip_shortening_; }    ///< k (coefficient of m), >= 0
  double operatingPressureAngle() const { return alpha_w_; }  ///< alpha_w
  double centerDistance() const { return a_w_; }              ///< a_w
  double backlash() const { return backlash_; }               ///< [m] on the operating pitch circle
  double basePitch() const { return pb_; }                    ///< p_b = pi m cos(alpha)
  double lineOfActionLength() const { return t1t2_; }         ///< T1T2 = a_w sin(alpha_w)
  double pathStart() const { return s_a_; }                   ///< s_A
  double pathEnd() const { return s_e_; }                     ///< s_E
  double pitchPoint() const { return s_p_; }  ///< s of the pitch point = r_b1 tan(alpha_w)
  double contactRatio() const { return (s_e_ - s_a_) / pb_; }   ///< eps_alpha
  double backFlankPhaseOffset() const { return back_offset_; }  ///< s_w1 / p_w [mesh periods]

  /// The mesh phase [0, 1) of a pinion angle [rad].
  double phase(double pinion_angle) const;
  /// The contact at s [m], s_A <= s <= s_E.
  ContactPoint contactAt(double s) const;
  /// The drive pairs' s [m] at phase phi; returns how many (1..3).
  int drivePairs(double phi, std::array<double, 3>& s) const;
  /// The back pairs' s [m] on the mirrored LOA at phase phi; returns how many.
  int backPairs(double phi, std::array<double, 3>& s) const;

 private:
  /// The constructor's steps in order, each throwing InvalidInput naming the field: the reference,
  /// base and root circles (undercut); the operating centre distance and pressure angle; the tips
  /// and tooth thickness; the backlash, the path of contact and the back-flank phase.
  void setReferenceCircles();
  void setCentreDistance();
  void setTips();
  void setPathOfContact();
  GearPairSpec spec_;
  std::array<double, 2> r_{}, rb_{}, ra_{}, rf_{}, rw_{}, alpha2_{}, sw_{};
  double tip_shortening_ = 0, alpha_w_ = 0, a_w_ = 0, backlash_ = 0, pb_ = 0, t1t2_ = 0;
  double s_a_ = 0, s_e_ = 0, s_p_ = 0, back_offset_ = 0, back_origin_ = 0;
};

/// inv(alpha) = tan(alpha) - alpha.
double involute(double alpha);
/// Inverse involute by Newton's method (inv is monotone on [0, pi/2)).
double inverseInvolute(double value);

/// Base radius r_b = m z cos(alpha) / 2 (ISO 21771:2007, d_b = d cos(alpha_t), d = m z) [m].
double baseRadius(const GearPairSpec& spec, int gear_index);
/// Normal mesh force along the LOA from a torque on gear `gear_index`: F = T / r_b (seed 000 eq 14,
/// F_m = T_p / r_p) [N]; sign follows the torque.
double meshForce(const GearPairSpec& spec, int gear_index, double torque);
/// Field-level checks of a spec without building the geometry (module, angles, teeth, shifts).
void validateGearPair(const GearPairSpec& spec);

}  // namespace drivetrain_stiffness

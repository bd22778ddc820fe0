// Involute spur gear pair geometry (external gears, ISO 21771:2007 notation), the path of contact
// and the mesh phase.
//
// Along the line of action (LOA), s is measured from T1, the tangent point on the pinion's base
// circle (T1T2 = a_w sin(alpha_w)). A tooth pair is in contact from s_A = T1T2 - sqrt(ra2^2 -
// rb2^2) (gear tip on the pinion root flank) to s_E = sqrt(ra1^2 - rb1^2) (pinion tip); the contact
// ratio is eps_alpha = (s_E - s_A) / p_b with the base pitch p_b = pi m cos(alpha). Mesh phase phi
// in [0, 1): fraction of a mesh period (one pinion angular pitch 2 pi / z1) since a drive-flank
// pair entered contact at s_A; pinion angle 0 is such an entry. Drive pair k sits at s = s_A + (phi
// + k) p_b; two pairs carry load for phi in [0, eps_alpha - 1] (seed 000 eq 2's s_i). Back (coast)
// flank pairs, meshing with the loaded half g2 of an anti-backlash gear, run along the mirrored LOA
// from the pinion tip to its root, and reach the pitch point a pinion rotation of s_w1 / r_w1 (the
// operating tooth thickness) after the drive flank of the same tooth does: their curve is the drive
// curve mirrored and shifted in phase (Guo & Parker, Mech. Mach. Theory 78 (2014) 263, back-side
// stiffness "phase-shifted"; the shift is derived in docs/gear_model.md).
#pragma once

#include <array>
#include <optional>

#include "drivetrain_stiffness/core/interference_fit.hpp"

namespace drivetrain_stiffness {

struct GearPairSpec {
  double module = 0.0;               ///< m (normal module) [m]
  double pressure_angle = 0.0;       ///< alpha (normal) [rad]
  double helix_angle = 0.0;          ///< beta [rad]; only the ISO 6336 baseline uses it
  std::array<int, 2> teeth{{0, 0}};  ///< z_pinion, z_gear
  std::array<double, 2> profile_shift{{0.0, 0.0}};  ///< x (coefficient of m)
  double addendum_coefficient = 1.0;                ///< h_aP* of the basic rack (ISO 53: 1.0)
  double tool_dedendum_coefficient = 1.25;          ///< h_fP* of the basic rack (ISO 53: 1.25)
  double face_width = 0.0;                          ///< b [m]
  std::optional<double> center_distance;   ///< a_w [m]; default: tight (zero-backlash) mesh
  ElasticMaterial material{2.06e11, 0.3};  ///< both gears
  std::array<double, 2> bore_diameter{
      {0.0, 0.0}};  ///< rim/hub bore for the fillet foundation [m]; 0 = r_f/2 (h_f = 2)
};

/// A contact point on the LOA and the radii at which it lies on each gear.
struct ContactPoint {
  double s = 0.0;                            ///< position along the LOA from T1 [m]
  std::array<double, 2> radius{{0.0, 0.0}};  ///< r_c on pinion, gear [m]
  std::array<double, 2> pressure_angle{
      {0.0, 0.0}};  ///< alpha_c = acos(r_b / r_c) on pinion, gear [rad]
};

class SpurGearGeometry {
 public:
  /// Validates everything (undercut, pointed tips, interference, contact ratio >= 1, reachable
  /// centre distance) and throws InvalidInput naming the field and value.
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
  double backlash() const {
    return backlash_;
  }                                         ///< circumferential, on the operating pitch circle [m]
  double basePitch() const { return pb_; }  ///< p_b = pi m cos(alpha)
  double lineOfActionLength() const { return t1t2_; }  ///< T1T2 = a_w sin(alpha_w)
  double pathStart() const { return s_a_; }            ///< s_A
  double pathEnd() const { return s_e_; }              ///< s_E
  double pitchPoint() const { return s_p_; }           ///< s of the pitch point = r_b1 tan(alpha_w)
  double contactRatio() const { return (s_e_ - s_a_) / pb_; }   ///< eps_alpha
  double backFlankPhaseOffset() const { return back_offset_; }  ///< s_w1 / p_w, in mesh periods

  /// Mesh phase of a pinion rotation angle [rad] (any real number).
  double phase(double pinion_angle) const;
  /// Contact geometry at LOA position s (s_A <= s <= s_E).
  ContactPoint contactAt(double s) const;
  /// LOA positions of the drive-flank pairs in contact at phase phi; returns how many (1..3).
  int drivePairs(double phi, std::array<double, 3>& s) const;
  /// LOA positions (on the mirrored back LOA) of the back-flank pairs in contact at phase phi.
  int backPairs(double phi, std::array<double, 3>& s) const;

 private:
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

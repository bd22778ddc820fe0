#include "drivetrain_stiffness/core/gear/gear_geometry.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
std::string gearField(const char* name, int i) {
  return std::string("gears.") + name + "[" + std::to_string(i) + "]";
}
}  // namespace

double involute(double alpha) { return std::tan(alpha) - alpha; }

double inverseInvolute(double value) {
  requireNonNegative("involute", value);
  // Starting guess from the series inv(a) ~ a^3/3 (good for small angles); Newton on tan(a) - a.
  double a = std::min(std::cbrt(3.0 * value), 1.5);
  for (int i = 0; i < 60; ++i) {
    const double f = std::tan(a) - a - value;
    const double df = std::tan(a) * std::tan(a);  // d inv / d alpha = tan^2(alpha)
    if (df <= 0.0) {
      a = 1e-8;
      continue;
    }
    const double next = std::clamp(a - f / df, 0.5 * a, 0.5 * (a + kPi / 2.0));
    if (std::abs(next - a) < 1e-15) return next;
    a = next;
  }
  return a;
}

void validateGearPair(const GearPairSpec& spec) {
  requirePositive("gears.module", spec.module);
  requireAtMost("gears.module", spec.module, 1.0);  // [m]; the largest gears made have ~0.1 m
  requireInOpenRange("gears.pressure_angle_deg", spec.pressure_angle * 180.0 / kPi, 0.0, 45.0);
  requireInHalfOpenRange("gears.helix_angle_deg", spec.helix_angle * 180.0 / kPi, 0.0, 45.0);
  for (int i = 0; i < 2; ++i) {
    if (spec.teeth[i] < 5 || spec.teeth[i] > 100000)
      throwInvalid(gearField("teeth", i), spec.teeth[i], "must be an integer >= 5");
    requireInOpenRange(gearField("profile_shift", i), spec.profile_shift[i], -2.0, 2.0);
    requireNonNegative(gearField("bore_diameter", i), spec.bore_diameter[i]);
  }
  requireInOpenRange("gears.addendum_coefficient", spec.addendum_coefficient, 0.0, 2.0);
  requireInOpenRange("gears.tool_dedendum_coefficient", spec.tool_dedendum_coefficient, 0.0, 3.0);
  requireNonNegative("gears.face_width", spec.face_width);
  requireAtMost("gears.face_width", spec.face_width, 10.0);  // [m]
  requireYoungsModulus("gears.youngs_modulus", spec.material.youngs_modulus);
  requireInHalfOpenRange("gears.poisson_ratio", spec.material.poisson_ratio, 0.0, 0.5);
  if (spec.center_distance) requirePositive("gears.center_distance", *spec.center_distance);
}

double baseRadius(const GearPairSpec& spec, int gear_index) {
  if (gear_index != 0 && gear_index != 1)
    throwInvalid("gear_index", gear_index, "must be 0 (pinion) or 1 (gear)");
  return 0.5 * spec.module * spec.teeth[gear_index] * std::cos(spec.pressure_angle);
}

double meshForce(const GearPairSpec& spec, int gear_index, double torque) {
  requireFinite("torque", torque);
  return torque / baseRadius(spec, gear_index);
}

SpurGearGeometry::SpurGearGeometry(const GearPairSpec& spec) : spec_(spec) {
  validateGearPair(spec);
  setReferenceCircles();
  setCentreDistance();
  setTips();
  setPathOfContact();
}

void SpurGearGeometry::setReferenceCircles() {
  const GearPairSpec& spec = spec_;
  const double m = spec.module, alpha = spec.pressure_angle, ha = spec.addendum_coefficient;
  for (int i = 0; i < 2; ++i) {
    const int z = spec.teeth[i];
    const double x = spec.profile_shift[i];
    // Undercut by the generating rack: x >= h_a - z sin^2(alpha) / 2 (ISO 21771 / Niemann-Winter).
    const double x_min = ha - 0.5 * z * std::sin(alpha) * std::sin(alpha);
    if (x < x_min - 1e-12) {
      throw InvalidInput(gearField("teeth", i) + " = " + std::to_string(z) + " with " +
                         gearField("profile_shift", i) + " = " + formatValue(x) +
                         ": undercut; needs profile_shift >= " + formatValue(x_min));
    }
    r_[i] = 0.5 * m * z;
    rb_[i] = r_[i] * std::cos(alpha);
    rf_[i] = r_[i] - m * (spec.tool_dedendum_coefficient - x);
    alpha2_[i] = kPi / (2.0 * z) + 2.0 * x * std::tan(alpha) / z + involute(alpha);
    if (!(rf_[i] > 0.0)) throwInvalid(gearField("teeth", i), z, "root radius is not positive");
  }
}

void SpurGearGeometry::setCentreDistance() {
  const GearPairSpec& spec = spec_;
  const double alpha = spec.pressure_angle;
  const double a0 = r_[0] + r_[1];
  const double x_sum = spec.profile_shift[0] + spec.profile_shift[1];
  // Tight-mesh operating pressure angle: inv(alpha_w) = inv(alpha) + 2 tan(alpha) (x1 + x2) / (z1 +
  // z2).
  const double alpha_tight = inverseInvolute(involute(alpha) + 2.0 * std::tan(alpha) * x_sum /
                                                                   (spec.teeth[0] + spec.teeth[1]));
  const double a_tight = a0 * std::cos(alpha) / std::cos(alpha_tight);
  if (spec.center_distance) {
    a_w_ = *spec.center_distance;
    if (a_w_ < a_tight * (1.0 - 1e-9)) {
      throwInvalid("gears.center_distance", a_w_,
                   "is below the tight-mesh distance " + formatValue(a_tight) +
                       " m: the teeth would interpenetrate");
    }
    alpha_w_ = std::acos(a0 * std::cos(alpha) / a_w_);
  } else {
    a_w_ = a_tight;
    alpha_w_ = alpha_tight;
  }
}

void SpurGearGeometry::setTips() {
  const GearPairSpec& spec = spec_;
  const double m = spec.module, alpha = spec.pressure_angle, ha = spec.addendum_coefficient;
  const double a0 = r_[0] + r_[1];
  const double x_sum = spec.profile_shift[0] + spec.profile_shift[1];
  // Tip shortening keeps the bottom clearance when x1 + x2 > (a_w - a0) / m (Niemann & Winter,
  // Maschinenelemente II, sec. 21; ISO 21771 sec. 5.4 "tip alteration").
  tip_shortening_ = std::max(0.0, x_sum - (a_w_ - a0) / m);
  for (int i = 0; i < 2; ++i) {
    ra_[i] = r_[i] + m * (ha + spec.profile_shift[i] - tip_shortening_);
    rw_[i] = rb_[i] / std::cos(alpha_w_);
    // Tooth thickness on a circle of pressure angle a: s = 2 r_c (s_0/(2r) + inv(alpha) - inv(a)),
    // s_0 = m (pi/2 + 2 x tan(alpha)) (ISO 21771).
    const double s0_half_angle =
        (kPi / 2.0 + 2.0 * spec.profile_shift[i] * std::tan(alpha)) / spec.teeth[i];
    sw_[i] = 2.0 * rw_[i] * (s0_half_angle + involute(alpha) - involute(alpha_w_));
    const double alpha_a = std::acos(rb_[i] / ra_[i]);
    const double tip_thickness =
        2.0 * ra_[i] * (s0_half_angle + involute(alpha) - involute(alpha_a));
    if (tip_thickness < 0.0) {
      throwInvalid(gearField("profile_shift", i), spec.profile_shift[i],
                   "gives pointed teeth (negative tip thickness)");
    }
  }
}

void SpurGearGeometry::setPathOfContact() {
  const GearPairSpec& spec = spec_;
  const double m = spec.module, alpha = spec.pressure_angle, ha = spec.addendum_coefficient;
  backlash_ = 2.0 * kPi * rw_[0] / spec.teeth[0] - sw_[0] - sw_[1];
  pb_ = kPi * m * std::cos(alpha);
  t1t2_ = a_w_ * std::sin(alpha_w_);
  s_e_ = std::sqrt(ra_[0] * ra_[0] - rb_[0] * rb_[0]);
  s_a_ = t1t2_ - std::sqrt(ra_[1] * ra_[1] - rb_[1] * rb_[1]);
  s_p_ = rb_[0] * std::tan(alpha_w_);
  if (s_a_ < 0.0 || s_e_ > t1t2_) {
    throw InvalidInput("gears: involute interference: the path of contact [" + formatValue(s_a_) +
                       ", " + formatValue(s_e_) + "] m leaves the line of action [0, " +
                       formatValue(t1t2_) + "] m (tip of one gear below the other's base circle)");
  }
  if (contactRatio() < 1.0) {
    throwInvalid("gears.center_distance", a_w_,
                 "gives a transverse contact ratio " + formatValue(contactRatio()) + " < 1");
  }
  if (a_w_ - ra_[0] - rf_[1] < 0.0 || a_w_ - ra_[1] - rf_[0] < 0.0) {
    throwInvalid("gears.addendum_coefficient", ha,
                 "tips reach the other gear's root circle (no bottom clearance)");
  }
  // Back-flank phase: the back flank of a pinion tooth reaches the pitch point s_w1 / r_w1 of
  // pinion rotation after its drive flank, i.e. s_w1 / p_w mesh periods later (p_w = 2 pi r_w1 /
  // z1).
  back_offset_ = sw_[0] / (2.0 * kPi * rw_[0] / spec.teeth[0]);
  // Back pair k sits at s' = back_origin - (phi + k) p_b: moving from the pinion tip to its root.
  back_origin_ = s_p_ + (s_p_ - s_a_) + back_offset_ * pb_;
}

double SpurGearGeometry::phase(double pinion_angle) const {
  requireFinite("pinion_angle", pinion_angle);
  const double turns = pinion_angle * spec_.teeth[0] / (2.0 * kPi);
  return turns - std::floor(turns);
}

ContactPoint SpurGearGeometry::contactAt(double s) const {
  ContactPoint c;
  c.s = s;
  const double s_gear = t1t2_ - s;
  c.radius = {std::sqrt(rb_[0] * rb_[0] + s * s), std::sqrt(rb_[1] * rb_[1] + s_gear * s_gear)};
  c.pressure_angle = {std::atan2(s, rb_[0]), std::atan2(s_gear, rb_[1])};
  return c;
}

int SpurGearGeometry::drivePairs(double phi, std::array<double, 3>& s) const {
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const double pos = s_a_ + (phi + k) * pb_;
    if (pos <= s_e_ * (1.0 + 1e-12)) s[n++] = std::min(pos, s_e_);
  }
  return n;
}

int SpurGearGeometry::backPairs(double phi, std::array<double, 3>& s) const {
  // s' = back_origin - (phi + k) p_b for integers k: start from the largest s' <= s_E and walk
  // down the path in steps of p_b while s' >= s_A (at most 3 pairs for eps_alpha < 3).
  double pos = back_origin_ - phi * pb_;
  pos -= std::ceil((pos - s_e_) / pb_ - 1e-12) * pb_;
  int n = 0;
  for (; n < 3 && pos >= s_a_ * (1.0 - 1e-12); pos -= pb_) s[n++] = std::max(pos, s_a_);
  return n;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/core/bearing/hertz_contact.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/enum_names.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

// F(rho) as a function of ln(kappa) for kappa > 1: [(k^2+1)E - 2F] / [(k^2-1)E]
// (Hamrock & Brewe 1983, the exact ellipticity relation solved for F(rho)). Monotonically
// increasing from 0 at kappa = 1.
double curvatureDifferenceOf(double log_kappa) {
  const double kappa = std::exp(log_kappa);
  const double modulus = std::sqrt(1.0 - 1.0 / (kappa * kappa));
  const double first = std::comp_ellint_1(modulus);
  const double second = std::comp_ellint_2(modulus);
  return ((kappa * kappa + 1.0) * second - 2.0 * first) / ((kappa * kappa - 1.0) * second);
}
}  // namespace

namespace {
constexpr EnumName<EllipticityMethod> kEllipticityMethods[] = {
    {EllipticityMethod::kExact, "exact"}, {EllipticityMethod::kHamrockDowson, "hamrock_dowson"}};
}  // namespace

EllipticityMethod parseEllipticityMethod(const std::string& field, const std::string& text) {
  return parseEnum(kEllipticityMethods, field, text);
}
const char* toString(EllipticityMethod method) { return enumName(kEllipticityMethods, method); }

double reducedModulus(double youngs_a, double poisson_a, double youngs_b, double poisson_b) {
  requirePositive("youngs_modulus", youngs_a);
  requirePositive("youngs_modulus", youngs_b);
  requireInHalfOpenRange("poisson_ratio", poisson_a, 0.0, 0.5);
  requireInHalfOpenRange("poisson_ratio", poisson_b, 0.0, 0.5);
  return 2.0 /
         ((1.0 - poisson_a * poisson_a) / youngs_a + (1.0 - poisson_b * poisson_b) / youngs_b);
}

EllipticityParameters exactEllipticity(double curvature_difference) {
  requireInHalfOpenRange("curvature_difference", curvature_difference, 0.0, 1.0);
  EllipticityParameters out;
  if (curvature_difference < 1e-12) {  // circular contact: kappa = 1, E = F = pi/2
    out.ellipticity = 1.0;
    out.elliptic_first = out.elliptic_second = kPi / 2.0;
    return out;
  }
  // Bracket ln(kappa) and refine with the Illinois variant of regula falsi: robust (the function
  // is monotone) and converges superlinearly; the starting bracket comes from the
  // Hamrock-Dowson kappa fit written in terms of F(rho).
  double lo = 1e-9, hi = 1.0;
  while (curvatureDifferenceOf(hi) < curvature_difference && hi < 40.0) hi *= 2.0;
  double f_lo = curvatureDifferenceOf(lo) - curvature_difference;
  double f_hi = curvatureDifferenceOf(hi) - curvature_difference;
  int side = 0;
  double x = hi;
  for (int i = 0; i < 200; ++i) {
    x = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    const double fx = curvatureDifferenceOf(x) - curvature_difference;
    if (std::abs(fx) < 1e-15 || (hi - lo) < 1e-15 * std::max(1.0, x)) break;
    if (fx * f_hi > 0.0) {
      hi = x;
      f_hi = fx;
      if (side == -1) f_lo /= 2.0;
      side = -1;
    } else {
      lo = x;
      f_lo = fx;
      if (side == 1) f_hi /= 2.0;
      side = 1;
    }
  }
  out.ellipticity = std::exp(x);
  const double modulus = std::sqrt(1.0 - 1.0 / (out.ellipticity * out.ellipticity));
  out.elliptic_first = std::comp_ellint_1(modulus);
  out.elliptic_second = std::comp_ellint_2(modulus);
  return out;
}

EllipticityParameters hamrockDowsonEllipticity(double radius_ratio_y_over_x) {
  requireFinite("ry_over_rx", radius_ratio_y_over_x);
  if (radius_ratio_y_over_x < 1.0)
    throwInvalid("ry_over_rx", radius_ratio_y_over_x, "must be >= 1");
  EllipticityParameters out;
  // Seed 000 eq 8 (Hamrock & Dowson 1981 fits); seed letters e, L, F are kappa, script E, script F.
  out.ellipticity = 1.0339 * std::pow(radius_ratio_y_over_x, 0.636);
  out.elliptic_second = 1.0003 + 0.5968 / radius_ratio_y_over_x;
  out.elliptic_first = 1.5277 + 0.6023 * std::log(radius_ratio_y_over_x);
  return out;
}

HertzPointContact::HertzPointContact(double rx, double ry, double reduced_modulus,
                                     EllipticityMethod method)
    : rx_(rx), ry_(ry), reduced_modulus_(reduced_modulus) {
  requirePositive("rx", rx);
  requirePositive("ry", ry);
  requirePositive("reduced_modulus", reduced_modulus);
  // Ry < Rx would give kappa < 1 and a contact several times too stiff (bearing.md pitfall 2).
  if (ry < rx * (1.0 - 1e-12)) {
    throw InvalidInput("ry = " + formatValue(ry) + " < rx = " + formatValue(rx) +
                       ": principal radii swapped (Ry must be >= Rx)");
  }
  r_ = 1.0 / (1.0 / rx + 1.0 / ry);
  f_rho_ = std::max(0.0, r_ * (1.0 / rx - 1.0 / ry));
  ellipticity_ = method == EllipticityMethod::kExact ? exactEllipticity(f_rho_)
                                                     : hamrockDowsonEllipticity(ry / rx);
  const double kappa = ellipticity_.ellipticity;
  const double e2 = ellipticity_.elliptic_second;
  const double f1 = ellipticity_.elliptic_first;
  k_ = kPi * kappa * reduced_modulus_ * std::sqrt(2.0 * e2 * r_ / (9.0 * f1 * f1 * f1));
}

double HertzPointContact::load(double deflection) const {
  return deflection > 0.0 ? k_ * deflection * std::sqrt(deflection) : 0.0;
}

double HertzPointContact::deflection(double load) const {
  requireNonNegative("load", load);
  return std::pow(load / k_, 2.0 / 3.0);
}

double HertzPointContact::semiMajorAxis(double load) const {
  requireNonNegative("load", load);
  const double kappa = ellipticity_.ellipticity;
  return std::cbrt(6.0 * kappa * kappa * ellipticity_.elliptic_second * load * r_ /
                   (kPi * reduced_modulus_));
}

double HertzPointContact::semiMinorAxis(double load) const {
  requireNonNegative("load", load);
  return std::cbrt(6.0 * ellipticity_.elliptic_second * load * r_ /
                   (kPi * ellipticity_.ellipticity * reduced_modulus_));
}

double HertzPointContact::maxPressure(double load) const {
  if (load <= 0.0) return 0.0;
  return 3.0 * load / (2.0 * kPi * semiMajorAxis(load) * semiMinorAxis(load));
}

double combinedLoadDeflectionConstant(double k_inner, double k_outer) {
  requirePositive("k_inner", k_inner);
  requirePositive("k_outer", k_outer);
  return std::pow(std::pow(k_inner, -2.0 / 3.0) + std::pow(k_outer, -2.0 / 3.0), -1.5);
}

}  // namespace drivetrain_stiffness

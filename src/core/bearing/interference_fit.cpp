#include "drivetrain_stiffness/core/bearing/interference_fit.hpp"

#include <cmath>
#include <string>
#include <string_view>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

// The field names are built only when a check fails: a preload input that changes an interference
// or an axial preload rebuilds its support's bearing, and with it these fits, on the per-input path
// (no heap allocation there: allocation_tests).
void validateMaterial(std::string_view prefix, const ElasticMaterial& m) {
  const bool modulus_ok = std::isfinite(m.youngs_modulus) &&
                          m.youngs_modulus >= kMinYoungsModulus &&
                          m.youngs_modulus <= kMaxYoungsModulus;  // requireYoungsModulus's test
  if (!modulus_ok) requireYoungsModulus(std::string(prefix) + "youngs_modulus", m.youngs_modulus);
  const bool poisson_ok =
      std::isfinite(m.poisson_ratio) && m.poisson_ratio >= 0.0 && m.poisson_ratio < 0.5;
  if (!poisson_ok)
    requireInHalfOpenRange(std::string(prefix) + "poisson_ratio", m.poisson_ratio, 0.0, 0.5);
}

void requireLess(std::string_view small_name, double small, std::string_view big_name, double big) {
  if (!(small < big)) {
    throw InvalidInput(std::string(small_name) + " = " + formatValue(small) + " must be < " +
                       std::string(big_name) + " = " + formatValue(big));
  }
}

}  // namespace

FitResult innerRingFit(const InnerRingFit& fit) {
  requireNonNegative("inner_interference", fit.interference);
  requirePositive("bore_diameter", fit.bore_diameter);
  requirePositive("inner_raceway_diameter", fit.raceway_diameter);
  requireNonNegative("shaft_bore_diameter", fit.shaft_bore_diameter);
  requireLess("shaft_bore_diameter", fit.shaft_bore_diameter, "bore_diameter", fit.bore_diameter);
  requireLess("bore_diameter", fit.bore_diameter, "inner_raceway_diameter", fit.raceway_diameter);
  validateMaterial("ring.", fit.ring);
  validateMaterial("shaft.", fit.shaft);
  if (fit.interference == 0.0) return {};

  const double d2 = fit.bore_diameter * fit.bore_diameter;
  const double di2 = fit.raceway_diameter * fit.raceway_diameter;
  const double ds2 = fit.shaft_bore_diameter * fit.shaft_bore_diameter;
  // Compliances of ring (internal pressure) and shaft (external pressure) at the fit diameter.
  const double ring_term =
      ((di2 + d2) / (di2 - d2) + fit.ring.poisson_ratio) / fit.ring.youngs_modulus;
  const double shaft_term =
      ((d2 + ds2) / (d2 - ds2) - fit.shaft.poisson_ratio) / fit.shaft.youngs_modulus;
  FitResult out;
  out.contact_pressure = (fit.interference / fit.bore_diameter) / (ring_term + shaft_term);
  out.raceway_change = 2.0 * out.contact_pressure * d2 * fit.raceway_diameter /
                       (fit.ring.youngs_modulus * (di2 - d2));
  return out;
}

FitResult outerRingFit(const OuterRingFit& fit) {
  requireNonNegative("outer_interference", fit.interference);
  requirePositive("outside_diameter", fit.outside_diameter);
  requirePositive("outer_raceway_diameter", fit.raceway_diameter);
  if (std::isnan(fit.housing_outside_diameter)) {
    throwInvalid("housing_outside_diameter", fit.housing_outside_diameter,
                 "must be a number (inf: rigid-bodied housing)");
  }
  requireLess("outer_raceway_diameter", fit.raceway_diameter, "outside_diameter",
              fit.outside_diameter);
  requireLess("outside_diameter", fit.outside_diameter, "housing_outside_diameter",
              fit.housing_outside_diameter);
  validateMaterial("ring.", fit.ring);
  validateMaterial("housing.", fit.housing);
  if (fit.interference == 0.0) return {};

  const double od2 = fit.outside_diameter * fit.outside_diameter;
  const double do2 = fit.raceway_diameter * fit.raceway_diameter;
  // (Dh^2 + D^2)/(Dh^2 - D^2) tends to 1 for an infinitely thick housing.
  const double housing_ratio =
      std::isinf(fit.housing_outside_diameter)
          ? 1.0
          : (fit.housing_outside_diameter * fit.housing_outside_diameter + od2) /
                (fit.housing_outside_diameter * fit.housing_outside_diameter - od2);
  const double ring_term =
      ((od2 + do2) / (od2 - do2) - fit.ring.poisson_ratio) / fit.ring.youngs_modulus;
  const double housing_term =
      (housing_ratio + fit.housing.poisson_ratio) / fit.housing.youngs_modulus;
  FitResult out;
  out.contact_pressure = (fit.interference / fit.outside_diameter) / (ring_term + housing_term);
  out.raceway_change = 2.0 * out.contact_pressure * od2 * fit.raceway_diameter /
                       (fit.ring.youngs_modulus * (od2 - do2));
  return out;
}

}  // namespace drivetrain_stiffness

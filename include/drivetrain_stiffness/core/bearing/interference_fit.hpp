// Interference fit of a bearing ring: Lame thick cylinders, plane stress; diameters and
// interferences diametral [m] (docs/bearing_model.md "1. Model", "Interference fit").
#pragma once

#include <limits>

namespace drivetrain_stiffness {

struct ElasticMaterial {
  double youngs_modulus = 0.0;  ///< [Pa]
  double poisson_ratio = 0.0;   ///< [-]
};

/// Inner ring on a shaft.
struct InnerRingFit {
  double interference = 0.0;         ///< I [m], >= 0
  double bore_diameter = 0.0;        ///< d [m]
  double raceway_diameter = 0.0;     ///< d_i (groove bottom) [m]
  double shaft_bore_diameter = 0.0;  ///< d_s [m], 0: solid
  ElasticMaterial ring;
  ElasticMaterial shaft;
};

/// Outer ring in a housing.
struct OuterRingFit {
  double interference = 0.0;      ///< I [m], >= 0
  double outside_diameter = 0.0;  ///< D [m]
  double raceway_diameter = 0.0;  ///< d_o (groove bottom) [m]
  double housing_outside_diameter = std::numeric_limits<double>::infinity();  ///< D_h [m]
  ElasticMaterial ring;
  ElasticMaterial housing;
};

struct FitResult {
  double contact_pressure = 0.0;  ///< p [Pa]
  double raceway_change = 0.0;    ///< raceway growth (inner) or shrink (outer) [m]
};

/// Pressure p (Shigley 10th ed. eq 3-56) and raceway growth delta_i = 2 p d^2 d_i / (E_r (d_i^2 -
/// d^2)) (Timoshenko & Goodier sec. 28). Throws InvalidInput unless d_s < d < d_i.
FitResult innerRingFit(const InnerRingFit& fit);
/// As innerRingFit, mirrored: the raceway shrink (>= 0). Throws InvalidInput unless d_o < D < D_h.
FitResult outerRingFit(const OuterRingFit& fit);

}  // namespace drivetrain_stiffness

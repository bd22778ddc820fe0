// Interference fit of a bearing ring by thick-cylinder (Lame) theory, plane stress.
//
// The inner ring (bore d, raceway diameter d_i) pressed on a shaft (bore d_s, 0 for solid) grows
// at its raceway; the outer ring (outside diameter D, raceway d_o) pressed into a housing
// (outside diameter D_h, infinite for a rigid-bodied housing) shrinks at its raceway. Both reduce
// the diametral clearance: Pd' = Pd - delta_i - delta_e (seed 000 eq 10; bearing.md section 3).
// Contact pressure from the compatibility of radial displacements of two Lame cylinders
// (Shigley's Mechanical Engineering Design, 10th ed., eq 3-56, written with diameters):
//   p = (I/d) / { [(d_i^2 + d^2)/(d_i^2 - d^2) + nu_r]/E_r + [(d^2 + d_s^2)/(d^2 - d_s^2) -
//   nu_s]/E_s }
// Raceway (outer surface of the inner ring) diametral growth under internal pressure p
// (Timoshenko & Goodier, Theory of Elasticity, sec. 28, u(b) = 2 p a^2 b / (E (b^2 - a^2))):
//   delta_i = 2 p d^2 d_i / (E_r (d_i^2 - d^2))
// and the mirror images for the outer ring. All diameters and interferences diametral, in m.
#pragma once

#include <limits>

namespace drivetrain_stiffness {

struct ElasticMaterial {
  double youngs_modulus = 0.0;  ///< E [Pa]
  double poisson_ratio = 0.0;   ///< nu [-]
};

/// Inner ring on a shaft.
struct InnerRingFit {
  double interference = 0.0;         ///< diametral interference I [m], >= 0 (0: loose or line fit)
  double bore_diameter = 0.0;        ///< d [m]
  double raceway_diameter = 0.0;     ///< d_i, inner raceway (groove bottom) diameter [m]
  double shaft_bore_diameter = 0.0;  ///< d_s [m], 0 for a solid shaft
  ElasticMaterial ring;
  ElasticMaterial shaft;
};

/// Outer ring in a housing.
struct OuterRingFit {
  double interference = 0.0;      ///< diametral interference I [m], >= 0
  double outside_diameter = 0.0;  ///< D [m]
  double raceway_diameter = 0.0;  ///< d_o, outer raceway (groove bottom) diameter [m]
  double housing_outside_diameter = std::numeric_limits<double>::infinity();  ///< D_h [m]
  ElasticMaterial ring;
  ElasticMaterial housing;
};

struct FitResult {
  double contact_pressure = 0.0;  ///< p at the fitted surface [Pa]
  double raceway_change = 0.0;    ///< diametral growth (inner) or shrink (outer) of the raceway [m]
};

/// Validates the geometry (d_s < d < d_i; d_o < D < D_h) and returns pressure and raceway growth.
FitResult innerRingFit(const InnerRingFit& fit);
/// Validates the geometry and returns pressure and raceway shrink (a positive number).
FitResult outerRingFit(const OuterRingFit& fit);

}  // namespace drivetrain_stiffness

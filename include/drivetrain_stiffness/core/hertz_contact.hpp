// Hertz elliptical point contact between two elastic bodies (ball on raceway).
//
// Notation follows Hamrock & Dowson (Ball Bearing Lubrication, Wiley 1981) and Hamrock & Brewe,
// "Simplified solution for stresses and deformations", J. Lubr. Technol. 105 (1983) 171-177:
//   Rx, Ry  effective radii of curvature in the two principal planes (1/Rx = 1/r_ax + 1/r_bx, ...),
//           with Ry >= Rx (x is the rolling direction, y the transverse direction).
//   R       curvature sum radius, 1/R = 1/Rx + 1/Ry.
//   F(rho)  curvature difference R (1/Rx - 1/Ry).
//   kappa   ellipticity a/b >= 1, E_ and F_ the complete elliptic integrals of the second and first
//           kind of modulus e = sqrt(1 - 1/kappa^2) (script E and script F in Hamrock).
//   E'      reduced modulus 2 / [(1-nu_a^2)/E_a + (1-nu_b^2)/E_b].
// All quantities SI: m, N, Pa; the load-deflection constant K is in N/m^1.5.
#pragma once

#include <string>

namespace drivetrain_stiffness {

/// How the ellipticity and elliptic integrals are obtained.
enum class EllipticityMethod {
  kExact,          ///< Solve F(rho) = [(k^2+1)E - 2F] / [(k^2-1)E] with C++17 elliptic integrals.
  kHamrockDowson,  ///< Curve fits of Hamrock & Dowson (1981), quoted as seed 000 eq 8.
};

/// Parses "exact" / "hamrock_dowson"; throws InvalidInput naming `field` otherwise.
EllipticityMethod parseEllipticityMethod(const std::string& field, const std::string& text);
const char* toString(EllipticityMethod method);

/// Reduced (effective) modulus E' = 2 / [(1-nu_a^2)/E_a + (1-nu_b^2)/E_b] (Hamrock & Brewe 1983, J.
/// Lubr. Technol. 105:171).
double reducedModulus(double youngs_a, double poisson_a, double youngs_b, double poisson_b);

/// Ellipticity parameters of a contact.
struct EllipticityParameters {
  double ellipticity = 1.0;      ///< kappa = a/b
  double elliptic_first = 0.0;   ///< script F, complete elliptic integral of the first kind
  double elliptic_second = 0.0;  ///< script E, complete elliptic integral of the second kind
};

/// Exact ellipticity from the curvature difference F(rho) in [0, 1).
EllipticityParameters exactEllipticity(double curvature_difference);
/// Hamrock-Dowson fits (seed 000 eq 8): kappa = 1.0339 (Ry/Rx)^0.636, E = 1.0003 + 0.5968 Rx/Ry,
/// F = 1.5277 + 0.6023 ln(Ry/Rx).
EllipticityParameters hamrockDowsonEllipticity(double radius_ratio_y_over_x);

/// One elliptical point contact; immutable after construction.
class HertzPointContact {
 public:
  /// rx, ry: principal effective radii [m] (ry >= rx, else InvalidInput); reduced_modulus E' [Pa].
  HertzPointContact(double rx, double ry, double reduced_modulus, EllipticityMethod method);

  double rx() const { return rx_; }
  double ry() const { return ry_; }
  double curvatureSumRadius() const { return r_; }       ///< R [m]
  double curvatureDifference() const { return f_rho_; }  ///< F(rho) [-]
  const EllipticityParameters& ellipticity() const { return ellipticity_; }

  /// K in Q = K delta^1.5 [N/m^1.5]: K = pi kappa E' sqrt(2 E R / (9 F^3)), the Hamrock-Brewe
  /// deflection delta = F [9/(2 E R) (Q/(pi kappa E'))^2]^(1/3) solved for Q; it reduces to Hertz's
  /// (4/3) E* sqrt(R_sphere) for two spheres (Johnson, Contact Mechanics, 1985, eq 4.23).
  double loadDeflectionConstant() const { return k_; }
  double load(double deflection) const;     ///< Q [N] for approach delta [m] (0 for delta <= 0)
  double deflection(double load) const;     ///< delta [m] for Q [N] >= 0
  double semiMajorAxis(double load) const;  ///< a = (6 kappa^2 E Q R / (pi E'))^(1/3) [m]
  double semiMinorAxis(double load) const;  ///< b = (6 E Q R / (pi kappa E'))^(1/3) [m]
  double maxPressure(double load) const;    ///< p_max = 3 Q / (2 pi a b) [Pa]

 private:
  double rx_, ry_, reduced_modulus_, r_, f_rho_;
  EllipticityParameters ellipticity_;
  double k_;
};

/// Series combination of the inner and outer contacts of one ball (both carry the same load):
/// Kn = [Ki^(-2/3) + Ko^(-2/3)]^(-3/2): the deflections add, delta = (Q/Ki)^(2/3) + (Q/Ko)^(2/3)
/// (Harris & Kotzalas, Rolling Bearing Analysis 5th ed., Essential Concepts, ch. 7; seed 000 eq 7
/// writes the same sum with steel constants).
double combinedLoadDeflectionConstant(double k_inner, double k_outer);

}  // namespace drivetrain_stiffness

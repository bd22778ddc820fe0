// Hertz elliptical point contact (ball on raceway) in the notation of Hamrock & Brewe, J. Lubr.
// Technol. 105 (1983) 171-177: docs/bearing_model.md "1. Model". SI: m, N, Pa; K in N/m^1.5.
#pragma once

#include <string>

namespace drivetrain_stiffness {

enum class EllipticityMethod {
  kExact,          ///< F(rho) = [(k^2+1)E - 2F] / [(k^2-1)E] solved (Hamrock & Brewe 1983)
  kHamrockDowson,  ///< the Hamrock & Dowson (1981) fits, seed 000 eq 8
};

/// Parses "exact" / "hamrock_dowson"; throws InvalidInput naming `field` otherwise.
EllipticityMethod parseEllipticityMethod(const std::string& field, const std::string& text);
const char* toString(EllipticityMethod method);

/// E' = 2 / [(1-nu_a^2)/E_a + (1-nu_b^2)/E_b] [Pa] (Hamrock & Brewe 1983).
double reducedModulus(double youngs_a, double poisson_a, double youngs_b, double poisson_b);

struct EllipticityParameters {
  double ellipticity = 1.0;      ///< kappa = a/b
  double elliptic_first = 0.0;   ///< script F (first kind)
  double elliptic_second = 0.0;  ///< script E (second kind)
};

/// The exact ellipticity for a curvature difference F(rho) in [0, 1).
EllipticityParameters exactEllipticity(double curvature_difference);
/// The Hamrock-Dowson fits (seed 000 eq 8).
EllipticityParameters hamrockDowsonEllipticity(double radius_ratio_y_over_x);

class HertzPointContact {
 public:
  /// rx <= ry: principal radii [m] (else InvalidInput); reduced_modulus E' [Pa].
  HertzPointContact(double rx, double ry, double reduced_modulus, EllipticityMethod method);

  double rx() const { return rx_; }
  double ry() const { return ry_; }
  double curvatureSumRadius() const { return r_; }       ///< R [m]
  double curvatureDifference() const { return f_rho_; }  ///< F(rho) [-]
  const EllipticityParameters& ellipticity() const { return ellipticity_; }

  /// K in Q = K delta^1.5 [N/m^1.5]: pi kappa E' sqrt(2 E R / (9 F^3)) (Hamrock & Brewe 1983).
  double loadDeflectionConstant() const { return k_; }
  double load(double deflection) const;     ///< Q [N] for approach delta [m] (0 for delta <= 0)
  double deflection(double load) const;     ///< delta [m] for Q [N] >= 0
  double semiMajorAxis(double load) const;  ///< a [m] (Hamrock & Brewe 1983)
  double semiMinorAxis(double load) const;  ///< b [m] (Hamrock & Brewe 1983)
  double maxPressure(double load) const;    ///< 3 Q / (2 pi a b) [Pa]

 private:
  double rx_, ry_, reduced_modulus_, r_, f_rho_;
  EllipticityParameters ellipticity_;
  double k_;
};

/// Kn = [Ki^(-2/3) + Ko^(-2/3)]^(-3/2) [N/m^1.5] of a ball's two contacts in series (Harris &
/// Kotzalas 5th ed., Essential Concepts ch. 7; seed 000 eq 7).
double combinedLoadDeflectionConstant(double k_inner, double k_outer);

}  // namespace drivetrain_stiffness

// Quasi-static model of one ball bearing (rigid rings, Hertz ball contacts, no centrifugal or
// gyroscopic effects: the low-speed Jones-Harris model of seed 003 eqs 1-10 and seed 000 eqs 4-11).
//
// Ball j at azimuth psi_j = 2 pi j / Z. The inner groove curvature centre, relative to the outer
// one, sits at (seed 003 eqs 2, 6, 7 with the centred datum of bearing.md pitfall 3):
//   a_z = s + u_z + R_i (theta_x sin psi - theta_y cos psi)      (axial)
//   a_r = A - Pd'/2 + u_x cos psi + u_y sin psi                  (radial)
// where A = (f_i + f_o - 1) D (seed 003 eq 1), Pd' the mounted diametral clearance (seed 000 eq 10)
// and s an axial offset used by position-preloaded pairs (0 for a single bearing). The contact
// approach is delta = sqrt(a_z^2 + a_r^2) - A (seed 003 eq 5), the ball load Q = Kn delta^1.5
// (seed 000 eq 6) and the contact angle alpha = atan2(a_z, a_r) (seed 003 eq 4).
// Equilibrium (seed 003 eq 10) is the stationary point of the stored energy
//   U(q) = sum_j (2/5) Kn max(delta_j, 0)^2.5,  f = dU/dq,  K = d2U/dq2 (tangent, symmetric),
// which is convex in q. Per ball, in the (a_r, a_z) plane (bearing.md section 3, derived here):
//   k_rr = Kn delta^0.5 (1.5 cos^2 a + e sin^2 a), k_zz = Kn delta^0.5 (1.5 sin^2 a + e cos^2 a),
//   k_rz = Kn delta^0.5 (1.5 - e) sin a cos a,  e = delta / L,
// mapped to q by a_r = T_r q, a_z = T_z q: K = sum_j T^T k_j T (the Lim-Singh / Noel et al. 2013
// full matrix; seed 003 eq 13 keeps only its diagonal, and writes n A_j (.)^2/(A_j - A_0) with the
// wrong sine/cosine in its K44 numerator).
// The groove is modelled full on both sides; for an angular-contact bearing a ball loaded on the
// missing shoulder side (alpha < 0) is reported as an unreachable load.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/hertz_contact.hpp"
#include "drivetrain_stiffness/core/interference_fit.hpp"
#include "drivetrain_stiffness/core/types.hpp"

namespace drivetrain_stiffness {

enum class BearingType { kAngularContact, kDeepGroove };
BearingType parseBearingType(const std::string& field, const std::string& text);
const char* toString(BearingType type);

/// Dimensions and materials of the fitted parts; only needed when an interference is applied.
struct FitGeometry {
  double bore_diameter = 0.0;           ///< d [m]
  double outside_diameter = 0.0;        ///< D [m]
  double inner_raceway_diameter = 0.0;  ///< d_i [m]
  double outer_raceway_diameter = 0.0;  ///< d_o [m]
  double shaft_bore_diameter = 0.0;     ///< [m], 0 = solid shaft
  double housing_outside_diameter = std::numeric_limits<double>::infinity();  ///< [m]
  ElasticMaterial shaft;  ///< defaults to the ring material when not given
  ElasticMaterial housing;
};

/// Everything that defines one bearing. Exactly one of diametral_clearance / contact_angle is set.
struct BallBearingSpec {
  BearingType type = BearingType::kAngularContact;
  int balls = 0;                         ///< Z
  double ball_diameter = 0.0;            ///< D [m]
  double pitch_diameter = 0.0;           ///< d_m [m]
  double inner_groove_conformity = 0.0;  ///< f_i = r_i / D, > 0.5
  double outer_groove_conformity = 0.0;  ///< f_o = r_o / D, > 0.5
  std::optional<double>
      diametral_clearance;              ///< unmounted Pd [m] (may be negative: radial preload)
  std::optional<double> contact_angle;  ///< unmounted free contact angle [rad]
  double width = 0.0;                   ///< B [m], ball-plane spacing of a duplex pair (optional)
  ElasticMaterial material;             ///< balls and rings (steel: 2.07e11 Pa, 0.3)
  EllipticityMethod ellipticity = EllipticityMethod::kExact;
  std::optional<FitGeometry> fit;  ///< required when an interference is non-zero
  /// Largest admissible contact pressure [Pa]; ISO 76:2006 uses 4.2 GPa for the static load rating
  /// of ball bearings (other than self-aligning), beyond which permanent deformation is not
  /// negligible.
  double max_contact_pressure = 4.2e9;
};

/// Interference of the two rings, diametral [m]; both >= 0.
struct Interference {
  double inner = 0.0;
  double outer = 0.0;
};

/// State of one ball at a solved position.
struct BallState {
  double azimuth = 0.0;        ///< psi [rad]
  double contact_angle = 0.0;  ///< alpha [rad]
  double deflection = 0.0;     ///< delta [m], negative when out of contact (gap)
  double load = 0.0;           ///< Q [N]
  double max_pressure = 0.0;   ///< largest of inner and outer Hertz pressure [Pa]
  bool in_contact = false;
};

/// Result of evaluating the bearing at one position.
struct BearingEvaluation {
  double energy = 0.0;  ///< U [J]
  Vector5d force =
      Vector5d::Zero();  ///< f = dU/dq, load on the inner ring from the balls, sign-flipped
  Matrix5d stiffness = Matrix5d::Zero();  ///< K = d2U/dq2 (tangent)
};

class BallBearing {
 public:
  /// Validates `spec` and `interference`; throws InvalidInput naming the field on any bad value.
  BallBearing(const BallBearingSpec& spec, const Interference& interference = {});
  /// Becomes BallBearing(spec, interference) in place, reusing the per-ball storage (no allocation
  /// for the same number of balls): a support rebuilt for new preload settings. Throws what the
  /// constructor throws, before anything changes.
  void assign(const BallBearingSpec& spec, const Interference& interference);

  const BallBearingSpec& spec() const { return spec_; }
  double grooveCentreDistance() const { return d_.a0; }          ///< A [m]
  double unmountedClearance() const { return d_.pd_unmounted; }  ///< Pd [m]
  double innerRacewayGrowth() const { return d_.delta_inner; }   ///< [m]
  double outerRacewayShrink() const { return d_.delta_outer; }   ///< [m]
  double mountedClearance() const { return d_.pd_mounted; }      ///< Pd' [m]
  double freeContactAngle() const { return d_.alpha_free; }      ///< mounted, 0 if Pd' <= 0 [rad]
  double innerGrooveCentreRadius() const { return d_.ri; }       ///< R_i [m] (seed 003 eq 8)
  double loadDeflectionConstant() const { return kn_; }          ///< Kn [N/m^1.5]
  const HertzPointContact& innerContact() const { return inner_; }
  const HertzPointContact& outerContact() const { return outer_; }

  /// Energy, force and tangent stiffness at q with axial offset s (see header comment).
  BearingEvaluation evaluate(const Vector5d& q, double axial_offset = 0.0) const;
  /// Per-ball state at q.
  std::vector<BallState> balls(const Vector5d& q, double axial_offset = 0.0) const;
  /// The same into `out`, reusing its storage (no allocation once it holds `balls` entries).
  void balls(const Vector5d& q, double axial_offset, std::vector<BallState>& out) const;

  /// Pure-axial equilibrium (u_x = u_y = tilt = 0) for an axial load F_z >= 0: returns u_z [m].
  /// Closed-form geometry, scalar safeguarded Newton (bearing.md "closed forms under pure axial").
  double axialDisplacementForLoad(double axial_load) const;

 private:
  /// Scalars derived from the spec and the fit, computed before the contacts are built.
  struct Derived {
    double a0 = 0, pd_unmounted = 0, delta_inner = 0, delta_outer = 0, pd_mounted = 0;
    double alpha_free = 0, ri = 0, ar0 = 0;
  };
  static Derived derive(const BallBearingSpec& spec, const Interference& interference);
  /// cos and sin of every ball's azimuth, for spec_.balls.
  void setAzimuths();
  /// Radial and axial separation (a_r, a_z) of the groove curvature centres of ball j.
  void separation(int j, const Vector5d& q, double axial_offset, double& ar, double& az) const {
    ar = d_.ar0 + q[kUx] * cos_psi_[j] + q[kUy] * sin_psi_[j];
    az = axial_offset + q[kUz] + d_.ri * (q[kThetaX] * sin_psi_[j] - q[kThetaY] * cos_psi_[j]);
  }

  BallBearingSpec spec_;
  Derived d_;
  HertzPointContact inner_, outer_;
  double kn_ = 0;
  std::vector<double> cos_psi_, sin_psi_;
};

}  // namespace drivetrain_stiffness

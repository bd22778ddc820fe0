// Quasi-static model of one ball bearing: rigid rings, Hertz ball contacts, the low-speed
// Jones-Harris model of seed 003 eqs 1-10 and seed 000 eqs 4-11 (docs/bearing_model.md "1. Model").
// Coordinates q and loads f as in types.hpp.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/bearing/hertz_contact.hpp"
#include "drivetrain_stiffness/core/bearing/interference_fit.hpp"
#include "drivetrain_stiffness/core/types.hpp"

namespace drivetrain_stiffness {

enum class BearingType { kAngularContact, kDeepGroove };
BearingType parseBearingType(const std::string& field, const std::string& text);
const char* toString(BearingType type);

/// The fitted parts, needed for a non-zero interference.
struct FitGeometry {
  double bore_diameter = 0.0;                                                 ///< d [m]
  double outside_diameter = 0.0;                                              ///< D [m]
  double inner_raceway_diameter = 0.0;                                        ///< d_i [m]
  double outer_raceway_diameter = 0.0;                                        ///< d_o [m]
  double shaft_bore_diameter = 0.0;                                           ///< [m], 0: solid
  double housing_outside_diameter = std::numeric_limits<double>::infinity();  ///< [m]
  ElasticMaterial shaft;  ///< default: the ring material
  ElasticMaterial housing;
};

/// One bearing; exactly one of diametral_clearance and contact_angle is set.
struct BallBearingSpec {
  BearingType type = BearingType::kAngularContact;
  int balls = 0;                              ///< Z
  double ball_diameter = 0.0;                 ///< D [m]
  double pitch_diameter = 0.0;                ///< d_m [m]
  double inner_groove_conformity = 0.0;       ///< f_i = r_i / D, > 0.5
  double outer_groove_conformity = 0.0;       ///< f_o = r_o / D, > 0.5
  std::optional<double> diametral_clearance;  ///< unmounted Pd [m], < 0: radial preload
  std::optional<double> contact_angle;        ///< unmounted free contact angle [rad]
  double width = 0.0;                         ///< B [m], ball-plane spacing of a duplex pair
  ElasticMaterial material;                   ///< balls and rings
  EllipticityMethod ellipticity = EllipticityMethod::kExact;
  std::optional<FitGeometry> fit;
  /// [Pa] the largest admissible contact pressure (ISO 76:2006 static load rating).
  double max_contact_pressure = 4.2e9;
};

/// Diametral interference of the two rings [m], >= 0.
struct Interference {
  double inner = 0.0;
  double outer = 0.0;
};

struct BallState {
  double azimuth = 0.0;        ///< psi [rad]
  double contact_angle = 0.0;  ///< alpha [rad]
  double deflection = 0.0;     ///< delta [m], < 0: a gap
  double load = 0.0;           ///< Q [N]
  double max_pressure = 0.0;   ///< [Pa] inner or outer, the larger
  bool in_contact = false;
};

struct BearingEvaluation {
  double energy = 0.0;                    ///< U [J]
  Vector5d force = Vector5d::Zero();      ///< f = dU/dq (seed 003 eq 10)
  Matrix5d stiffness = Matrix5d::Zero();  ///< K = d2U/dq2, tangent
};

class BallBearing {
 public:
  /// Throws InvalidInput naming the field for a bad spec or interference.
  BallBearing(const BallBearingSpec& spec, const Interference& interference = {});
  /// BallBearing(spec, interference) in place, allocation-free for the same number of balls. Throws
  /// as the constructor, before anything changes.
  void assign(const BallBearingSpec& spec, const Interference& interference);

  const BallBearingSpec& spec() const { return spec_; }
  double grooveCentreDistance() const { return d_.a0; }          ///< A [m]
  double unmountedClearance() const { return d_.pd_unmounted; }  ///< Pd [m]
  double innerRacewayGrowth() const { return d_.delta_inner; }   ///< [m]
  double outerRacewayShrink() const { return d_.delta_outer; }   ///< [m]
  double mountedClearance() const { return d_.pd_mounted; }      ///< Pd' [m] (seed 000 eq 10)
  double freeContactAngle() const { return d_.alpha_free; }      ///< [rad] mounted, 0 if Pd' <= 0
  double innerGrooveCentreRadius() const { return d_.ri; }       ///< R_i [m] (seed 003 eq 8)
  double loadDeflectionConstant() const { return kn_; }          ///< Kn [N/m^1.5]
  const HertzPointContact& innerContact() const { return inner_; }
  const HertzPointContact& outerContact() const { return outer_; }

  /// U, f and K at q with axial offset s [m] (0 for a single bearing).
  BearingEvaluation evaluate(const Vector5d& q, double axial_offset = 0.0) const;
  /// Per-ball state at q.
  std::vector<BallState> balls(const Vector5d& q, double axial_offset = 0.0) const;
  /// The same into `out`, reusing its storage.
  void balls(const Vector5d& q, double axial_offset, std::vector<BallState>& out) const;

  /// u_z [m] of the pure-axial equilibrium under F_z >= 0 [N] (bearing.md "closed forms under pure
  /// axial").
  double axialDisplacementForLoad(double axial_load) const;

 private:
  struct Derived {
    double a0 = 0, pd_unmounted = 0, delta_inner = 0, delta_outer = 0, pd_mounted = 0;
    double alpha_free = 0, ri = 0, ar0 = 0;
  };
  static Derived derive(const BallBearingSpec& spec, const Interference& interference);
  void setAzimuths();
  /// (a_r, a_z) [m] of ball j (seed 003 eqs 2, 6, 7).
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

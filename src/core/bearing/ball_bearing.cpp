#include "drivetrain_stiffness/core/bearing/ball_bearing.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/enum_names.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
constexpr double kMaxDiameter = 10.0;  // [m]

void validateSpec(const BallBearingSpec& s) {
  if (s.balls < 3) throwInvalid("balls", s.balls, "must be an integer >= 3");
  requirePositive("ball_diameter", s.ball_diameter);
  requirePositive("pitch_diameter", s.pitch_diameter);
  // Past any bearing made (TBM main bearings are ~8 m): at 1e308 the ring geometry overflows and
  // the equilibrium comes out NaN instead of refused.
  requireAtMost("pitch_diameter", s.pitch_diameter, kMaxDiameter);
  if (!(s.pitch_diameter > s.ball_diameter)) {
    throwInvalid("pitch_diameter", s.pitch_diameter,
                 "must exceed ball_diameter = " + formatValue(s.ball_diameter));
  }
  // Balls must fit around the pitch circle without overlapping: Z D < pi d_m.
  if (s.balls * s.ball_diameter >= kPi * s.pitch_diameter) {
    throwInvalid("balls", s.balls, "balls of this diameter do not fit on the pitch circle");
  }
  requireInOpenRange("inner_groove_conformity", s.inner_groove_conformity, 0.5, 1.0);
  requireInOpenRange("outer_groove_conformity", s.outer_groove_conformity, 0.5, 1.0);
  if (s.diametral_clearance.has_value() == s.contact_angle.has_value()) {
    throw InvalidInput("bearing: give exactly one of diametral_clearance and contact_angle_deg");
  }
  if (s.contact_angle) requireInHalfOpenRange("contact_angle", *s.contact_angle, 0.0, kPi / 2.0);
  if (s.diametral_clearance) requireFinite("diametral_clearance", *s.diametral_clearance);
  requireNonNegative("width", s.width);
  requireYoungsModulus("youngs_modulus", s.material.youngs_modulus);
  requireInHalfOpenRange("poisson_ratio", s.material.poisson_ratio, 0.0, 0.5);
  requirePositive("max_contact_pressure", s.max_contact_pressure);
}

}  // namespace

namespace {
constexpr EnumName<BearingType> kBearingTypes[] = {
    {BearingType::kAngularContact, "angular_contact"}, {BearingType::kDeepGroove, "deep_groove"}};
}  // namespace

BearingType parseBearingType(const std::string& field, const std::string& text) {
  return parseEnum(kBearingTypes, field, text);
}
const char* toString(BearingType type) { return enumName(kBearingTypes, type); }

BallBearing::Derived BallBearing::derive(const BallBearingSpec& s,
                                         const Interference& interference) {
  validateSpec(s);
  requireNonNegative("inner_interference", interference.inner);
  requireNonNegative("outer_interference", interference.outer);
  Derived d;
  const double D = s.ball_diameter;
  d.a0 = (s.inner_groove_conformity + s.outer_groove_conformity - 1.0) * D;  // seed 003 eq 1
  // Free contact angle and diametral clearance: alpha0 = acos(1 - Pd / 2A) (seed 003 eq 3).
  d.pd_unmounted = s.diametral_clearance ? *s.diametral_clearance
                                         : 2.0 * d.a0 * (1.0 - std::cos(*s.contact_angle));
  if (interference.inner > 0.0 || interference.outer > 0.0) {
    if (!s.fit) {
      throw InvalidInput(
          "inner_interference = " + formatValue(interference.inner) +
          ", outer_interference = " + formatValue(interference.outer) +
          ": an interference needs the fit geometry (bore_diameter, outside_diameter, "
          "inner_raceway_diameter, outer_raceway_diameter)");
    }
    const FitGeometry& g = *s.fit;
    if (!(g.inner_raceway_diameter < s.pitch_diameter &&
          s.pitch_diameter < g.outer_raceway_diameter)) {
      throw InvalidInput("pitch_diameter = " + formatValue(s.pitch_diameter) +
                         " must lie between "
                         "inner_raceway_diameter = " +
                         formatValue(g.inner_raceway_diameter) +
                         " and outer_raceway_diameter = " + formatValue(g.outer_raceway_diameter));
    }
    InnerRingFit inner{interference.inner,    g.bore_diameter, g.inner_raceway_diameter,
                       g.shaft_bore_diameter, s.material,      g.shaft};
    OuterRingFit outer{interference.outer,         g.outside_diameter, g.outer_raceway_diameter,
                       g.housing_outside_diameter, s.material,         g.housing};
    d.delta_inner = innerRingFit(inner).raceway_change;
    d.delta_outer = outerRingFit(outer).raceway_change;
  }
  // Mounted clearance Pd' = Pd - delta_i - delta_e (seed 000 eq 10 with Pd diametral: the seed
  // calls u_r "radial clearance" but its formula needs the diametral value).
  d.pd_mounted = d.pd_unmounted - d.delta_inner - d.delta_outer;
  d.ar0 = d.a0 - d.pd_mounted / 2.0;  // radial groove-centre separation at the centred position
  if (!(d.ar0 > 0.0)) {
    throwInvalid("diametral_clearance", d.pd_mounted,
                 "mounted clearance must be < 2 (f_i + f_o - 1) D = " + formatValue(2.0 * d.a0) +
                     " or the balls can never touch both raceways");
  }
  d.alpha_free = d.ar0 < d.a0 ? std::acos(d.ar0 / d.a0) : 0.0;
  d.ri = s.pitch_diameter / 2.0 +
         (s.inner_groove_conformity - 0.5) * D * std::cos(d.alpha_free);  // seed 003 eq 8
  return d;
}

namespace {
// Principal radii of the ball-raceway contacts (Harris & Kotzalas, Essential Concepts, ch. 2;
// bearing.md section 3): gamma = D cos(alpha) / d_m, Rx = (D/2)(1 -/+ gamma), Ry = f D / (2f - 1).
HertzPointContact raceContact(const BallBearingSpec& s, double alpha, bool inner) {
  const double gamma = s.ball_diameter * std::cos(alpha) / s.pitch_diameter;
  const double f = inner ? s.inner_groove_conformity : s.outer_groove_conformity;
  const double rx = 0.5 * s.ball_diameter * (inner ? 1.0 - gamma : 1.0 + gamma);
  const double ry = f * s.ball_diameter / (2.0 * f - 1.0);
  const double e_prime = reducedModulus(s.material.youngs_modulus, s.material.poisson_ratio,
                                        s.material.youngs_modulus, s.material.poisson_ratio);
  return HertzPointContact(rx, ry, e_prime, s.ellipticity);
}
}  // namespace

BallBearing::BallBearing(const BallBearingSpec& spec, const Interference& interference)
    : spec_(spec),
      d_(derive(spec, interference)),
      inner_(raceContact(spec_, d_.alpha_free, true)),
      outer_(raceContact(spec_, d_.alpha_free, false)),
      kn_(combinedLoadDeflectionConstant(inner_.loadDeflectionConstant(),
                                         outer_.loadDeflectionConstant())) {
  setAzimuths();
}

void BallBearing::assign(const BallBearingSpec& spec, const Interference& interference) {
  // The constructor's steps in its order, everything that can throw before anything changes.
  const Derived d = derive(spec, interference);
  const HertzPointContact inner = raceContact(spec, d.alpha_free, true);
  const HertzPointContact outer = raceContact(spec, d.alpha_free, false);
  spec_ = spec;
  d_ = d;
  inner_ = inner;
  outer_ = outer;
  kn_ = combinedLoadDeflectionConstant(inner_.loadDeflectionConstant(),
                                       outer_.loadDeflectionConstant());
  setAzimuths();
}

void BallBearing::setAzimuths() {
  cos_psi_.resize(spec_.balls);  // the same ball count keeps the storage
  sin_psi_.resize(spec_.balls);
  for (int j = 0; j < spec_.balls; ++j) {
    const double psi = 2.0 * kPi * j / spec_.balls;
    cos_psi_[j] = std::cos(psi);
    sin_psi_[j] = std::sin(psi);
  }
}

BearingEvaluation BallBearing::evaluate(const Vector5d& q, double axial_offset) const {
  BearingEvaluation out;
  const double a0 = d_.a0, ri = d_.ri;
  double k[5][5] = {};  // accumulate in plain arrays, fold into Eigen at the end
  double f[5] = {};
  for (int j = 0; j < spec_.balls; ++j) {
    const double c = cos_psi_[j], s = sin_psi_[j];
    double ar, az;
    separation(j, q, axial_offset, ar, az);
    const double l = std::sqrt(ar * ar + az * az);
    const double delta = l - a0;
    if (delta <= 0.0) continue;
    const double root = std::sqrt(delta);
    const double load = kn_ * delta * root;  // Q = Kn delta^1.5 (seed 000 eq 6)
    out.energy += 0.4 * load * delta;        // (2/5) Kn delta^2.5
    const double nr = ar / l, nz = az / l;   // cos(alpha), sin(alpha)
    const double kn_dir = 1.5 * kn_ * root;  // dQ/d(delta)
    const double kt = load / l;              // geometric (contact-angle change) term
    const double krr = kn_dir * nr * nr + kt * nz * nz;
    const double kzz = kn_dir * nz * nz + kt * nr * nr;
    const double krz = (kn_dir - kt) * nr * nz;
    // T_r = [c, s, 0, 0, 0], T_z = [0, 0, 1, ri s, -ri c]
    const double tr[2] = {c, s};
    const double tz[3] = {1.0, ri * s, -ri * c};
    const double fr = load * nr, fz = load * nz;
    f[0] += fr * c;
    f[1] += fr * s;
    for (int m = 0; m < 3; ++m) f[2 + m] += fz * tz[m];
    for (int a = 0; a < 2; ++a) {
      for (int b = a; b < 2; ++b) k[a][b] += krr * tr[a] * tr[b];
      for (int b = 0; b < 3; ++b) k[a][2 + b] += krz * tr[a] * tz[b];
    }
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b) k[2 + a][2 + b] += kzz * tz[a] * tz[b];
  }
  for (int a = 0; a < 5; ++a) {
    out.force[a] = f[a];
    for (int b = a; b < 5; ++b) out.stiffness(a, b) = out.stiffness(b, a) = k[a][b];
  }
  return out;
}

std::vector<BallState> BallBearing::balls(const Vector5d& q, double axial_offset) const {
  std::vector<BallState> out;
  balls(q, axial_offset, out);
  return out;
}

void BallBearing::balls(const Vector5d& q, double axial_offset, std::vector<BallState>& out) const {
  out.resize(static_cast<std::size_t>(spec_.balls));
  for (int j = 0; j < spec_.balls; ++j) {
    double ar, az;
    separation(j, q, axial_offset, ar, az);
    BallState& b = out[j];
    b.azimuth = 2.0 * kPi * j / spec_.balls;
    b.contact_angle = std::atan2(az, ar);
    b.deflection = std::sqrt(ar * ar + az * az) - d_.a0;
    b.in_contact = b.deflection > 0.0;
    b.load = b.in_contact ? kn_ * std::pow(b.deflection, 1.5) : 0.0;
    b.max_pressure = std::max(inner_.maxPressure(b.load), outer_.maxPressure(b.load));
  }
}

double BallBearing::axialDisplacementForLoad(double axial_load) const {
  requireNonNegative("axial_load", axial_load);
  const double ar = d_.ar0, a0 = d_.a0, z = spec_.balls;
  // Displacement at first contact (half the axial play, bearing.md pitfall 3).
  const double u_contact = ar < a0 ? std::sqrt(a0 * a0 - ar * ar) : 0.0;
  if (axial_load == 0.0) return u_contact;
  // F(u) = Z Kn delta^1.5 sin(alpha): bearing.md "thrust equilibrium" with the centred datum.
  auto thrust = [&](double u, double* slope) {
    const double l = std::sqrt(ar * ar + u * u);
    const double delta = std::max(l - a0, 0.0);
    const double root = std::sqrt(delta);
    const double nz = u / l, nr = ar / l;
    *slope = z * (1.5 * kn_ * root * nz * nz + kn_ * delta * root / l * nr * nr);
    return z * kn_ * delta * root * nz;
  };
  double lo = u_contact, hi = std::max(u_contact, 1e-9) * 2.0 + 1e-6;
  double slope = 0.0;
  while (thrust(hi, &slope) < axial_load) {
    lo = hi;
    hi *= 2.0;
    if (hi > spec_.ball_diameter)
      throw UnreachableLoad("axial_load = " + formatValue(axial_load) +
                            " N exceeds what the bearing geometry can carry");
  }
  double u = hi;
  for (int i = 0; i < 100; ++i) {
    const double r = thrust(u, &slope) - axial_load;
    if (r > 0.0)
      hi = u;
    else
      lo = u;
    double next = slope > 0.0 ? u - r / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // safeguard: stay inside the bracket
    if (std::abs(next - u) <= 1e-15 + 1e-13 * u) return next;
    u = next;
  }
  return u;
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/core/gear/mesh_stiffness.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/enum_names.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

// 16-point Gauss-Legendre nodes and weights on [-1, 1] (Abramowitz & Stegun, Table 25.4).
constexpr std::array<double, 8> kNodes = {
    0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
    0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
constexpr std::array<double, 8> kWeights = {
    0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
    0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};

template <typename F>
double gauss(double a, double b, F&& f) {
  const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
  double sum = 0.0;
  for (std::size_t i = 0; i < kNodes.size(); ++i)
    sum += kWeights[i] * (f(mid - half * kNodes[i]) + f(mid + half * kNodes[i]));
  return sum * half;
}

// Sainsot, Velex & Duverger (2004) Table 1: X = A/theta_f^2 + B h_f^2 + C h_f/theta_f + D/theta_f +
// E h_f + F.
struct FilletCoefficients {
  double a, b, c, d, e, f;
};
constexpr FilletCoefficients kL{-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045};
constexpr FilletCoefficients kM{60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086};
constexpr FilletCoefficients kP{-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236};
constexpr FilletCoefficients kQ{-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904};

double filletFit(const FilletCoefficients& k, double hf, double theta) {
  return k.a / (theta * theta) + k.b * hf * hf + k.c * hf / theta + k.d / theta + k.e * hf + k.f;
}

// Hertz contact stiffness of a tooth pair, Yang & Lin (1987): k_h = pi E b / (4 (1 - nu^2)).
double hertzStiffness(const GearPairSpec& spec, double width) {
  const double nu = spec.material.poisson_ratio;
  return kPi * spec.material.youngs_modulus * width / (4.0 * (1.0 - nu * nu));
}

class PotentialEnergyModel : public ToothPairStiffness {
 public:
  PotentialEnergyModel(const SpurGearGeometry& g, double width)
      : g_(g), width_(width), k_h_(hertzStiffness(g.spec(), width)) {}
  double pairStiffness(const ContactPoint& c) const override {
    double compliance = 1.0 / k_h_;
    for (int i = 0; i < 2; ++i) compliance += tooth(i, c.pressure_angle[i]).total();
    return 1.0 / compliance;
  }
  ToothCompliance tooth(int i, double alpha_c) const {
    const GearPairSpec& s = g_.spec();
    const double rb = g_.baseRadius(i), alpha2 = g_.halfToothAngleAtBase(i), rf = g_.rootRadius(i);
    ToothCompliance t = toothBeamCompliance(rb, alpha2, rf, alpha_c, s.material.youngs_modulus,
                                            s.material.poisson_ratio, width_);
    // Load line crossing the centre line, measured from the root circle (Sainsot's u_f).
    const double rc = rb / std::cos(alpha_c), phi_c = alpha2 - involute(alpha_c);
    const double load_angle = std::tan(alpha_c) - alpha2;
    const double u_f = rc * std::cos(phi_c) - rc * std::sin(phi_c) * std::tan(load_angle) - rf;
    // Half tooth angle at the root circle: constant-thickness segment below the base circle, else
    // involute.
    const double theta_f = rf < rb * std::cos(alpha2) ? std::asin(rb * std::sin(alpha2) / rf)
                                                      : alpha2 - involute(std::acos(rb / rf));
    const double bore = s.bore_diameter[i] > 0.0 ? 0.5 * s.bore_diameter[i] : 0.5 * rf;
    t.fillet = filletFoundationCompliance(rf, theta_f, bore, u_f, load_angle,
                                          s.material.youngs_modulus, width_);
    return t;
  }

 private:
  const SpurGearGeometry& g_;
  double width_, k_h_;
};

// Kuang & Yang (1992) tooth stiffness per unit width as quoted in gear.md section 1.3, assumed in
// N/(mm um) (= 1e9 N/m^2): k(r) = (A0 + A1 X) + (A2 + A3 X)(r - R) / ((1 + X) m).
class KuangYangModel : public ToothPairStiffness {
 public:
  KuangYangModel(const SpurGearGeometry& g, double width) : g_(g), width_(width) {
    const GearPairSpec& s = g.spec();
    const double nu = s.material.poisson_ratio;
    k_h_unit_ = kPi * s.material.youngs_modulus / (4.0 * (1.0 - nu * nu));
  }
  double pairStiffness(const ContactPoint& c) const override {
    const double ki = tooth(0, c.radius[0]), kj = tooth(1, c.radius[1]);
    // Seed 000 eq 3: k = ki kj kh B / (ki kj + (ki + kj) kh): teeth and Hertz in series, times
    // width.
    return ki * kj * k_h_unit_ * width_ / (ki * kj + (ki + kj) * k_h_unit_);
  }
  bool verified() const override { return false; }

 private:
  double tooth(int i, double r) const {
    const GearPairSpec& s = g_.spec();
    const double n = s.teeth[i], x = s.profile_shift[i];
    const double a0 = 3.867 + 1.612 * n - 0.02916 * n * n + 0.0001553 * n * n * n;
    const double a1 = 17.060 + 0.7289 * n - 0.01728 * n * n + 0.0000999 * n * n * n;
    const double a2 = 2.637 - 1.222 * n + 0.02217 * n * n - 0.0001179 * n * n * n;
    const double a3 = -6.330 - 1.033 * n + 0.02068 * n * n - 0.0001130 * n * n * n;
    const double mm = s.module * 1e3, r_mm = r * 1e3, pitch_mm = g_.referenceRadius(i) * 1e3;
    const double k = (a0 + a1 * x) + (a2 + a3 * x) * (r_mm - pitch_mm) / ((1.0 + x) * mm);
    return std::max(k, 1e-3) * 1e9;  // N/(mm um) -> N/m^2
  }
  const SpurGearGeometry& g_;
  double width_, k_h_unit_;
};

class Iso6336Model : public ToothPairStiffness {
 public:
  Iso6336Model(const SpurGearGeometry& g, double width)
      : pair_(iso6336Stiffness(g.spec()).mesh_stiffness * width / g.contactRatio()) {}
  double pairStiffness(const ContactPoint&) const override { return pair_; }

 private:
  double pair_;
};

}  // namespace

namespace {
constexpr EnumName<MeshStiffnessModel> kMeshStiffnessModels[] = {
    {MeshStiffnessModel::kPotentialEnergy, "potential_energy"},
    {MeshStiffnessModel::kKuangYang, "kuang_yang"},
    {MeshStiffnessModel::kIso6336, "iso6336"}};
}  // namespace

MeshStiffnessModel parseMeshStiffnessModel(const std::string& field, const std::string& text) {
  return parseEnum(kMeshStiffnessModels, field, text);
}
const char* toString(MeshStiffnessModel model) { return enumName(kMeshStiffnessModels, model); }

ToothCompliance toothBeamCompliance(double rb, double alpha2, double x_root, double alpha_c,
                                    double youngs, double poisson, double width) {
  const double shear_modulus = youngs / (2.0 * (1.0 + poisson));
  const double rc = rb / std::cos(alpha_c), phi_c = alpha2 - involute(alpha_c);
  const double xc = rc * std::cos(phi_c), hc = rc * std::sin(phi_c);
  const double a1 = std::tan(alpha_c) - alpha2;  // load angle to the normal of the centre line
  const double c1 = std::cos(a1), s1 = std::sin(a1);
  ToothCompliance out;
  // Energy of a cantilever section of half-thickness h at x: M = F[(xc - x) cos a1 - hc sin a1],
  // I = (2/3) h^3 b, A = 2 h b; shear with the 1.2 factor of a rectangle.
  auto section = [&](double x, double h, double* b, double* s, double* a) {
    const double arm = (xc - x) * c1 - hc * s1;
    *b = arm * arm / (youngs * (2.0 / 3.0) * h * h * h * width);
    *s = 1.2 * c1 * c1 / (shear_modulus * 2.0 * h * width);
    *a = s1 * s1 / (youngs * 2.0 * h * width);
  };
  // Segment below the base circle: constant thickness 2 rb sin(alpha2) (Chen & Shao 2011).
  const double xb = rb * std::cos(alpha2), hb = rb * std::sin(alpha2);
  if (x_root < xb) {
    double b, s, a;
    out.bending += gauss(x_root, xb, [&](double x) {
      section(x, hb, &b, &s, &a);
      return b;
    });
    out.shear += gauss(x_root, xb, [&](double x) {
      section(x, hb, &b, &s, &a);
      return s;
    });
    out.axial += gauss(x_root, xb, [&](double x) {
      section(x, hb, &b, &s, &a);
      return a;
    });
  }
  // Involute segment, parametrised by the pressure angle a of the profile point:
  // r = rb / cos a, phi = alpha2 - inv(a), x = r cos phi, h = r sin phi,
  // dx/da = rb sin a / cos^2 a cos phi + r sin phi tan^2 a.
  const double a_start = x_root > xb ? std::acos(std::min(1.0, rb / x_root)) : 0.0;
  if (alpha_c > a_start) {
    auto integrand = [&](double a, int which) {
      const double r = rb / std::cos(a), phi = alpha2 - involute(a);
      const double x = r * std::cos(phi), h = r * std::sin(phi);
      const double dxda = rb * std::sin(a) / (std::cos(a) * std::cos(a)) * std::cos(phi) +
                          r * std::sin(phi) * std::tan(a) * std::tan(a);
      double b, s, ax;
      section(x, h, &b, &s, &ax);
      return (which == 0 ? b : which == 1 ? s : ax) * dxda;
    };
    out.bending += gauss(a_start, alpha_c, [&](double a) { return integrand(a, 0); });
    out.shear += gauss(a_start, alpha_c, [&](double a) { return integrand(a, 1); });
    out.axial += gauss(a_start, alpha_c, [&](double a) { return integrand(a, 2); });
  }
  return out;
}

double filletFoundationCompliance(double rf, double theta_f, double r_int, double u_f,
                                  double load_angle, double youngs, double width) {
  requirePositive("root_radius", rf);
  requirePositive("bore_radius", r_int);
  if (!(r_int < rf))
    throwInvalid("gears.bore_diameter", 2.0 * r_int,
                 "must be smaller than the root diameter " + formatValue(2.0 * rf));
  const double hf = rf / r_int, sf = 2.0 * rf * theta_f, ratio = u_f / sf;
  const double c = std::cos(load_angle), t = std::tan(load_angle);
  // Sainsot et al. (2004) eq 4: 1/k_f = cos^2(a_m)/(E b) [L (u_f/S_f)^2 + M (u_f/S_f) + P (1 + Q
  // tan^2 a_m)].
  return c * c / (youngs * width) *
         (filletFit(kL, hf, theta_f) * ratio * ratio + filletFit(kM, hf, theta_f) * ratio +
          filletFit(kP, hf, theta_f) * (1.0 + filletFit(kQ, hf, theta_f) * t * t));
}

Iso6336Stiffness iso6336Stiffness(const GearPairSpec& spec) {
  validateGearPair(spec);
  Iso6336Stiffness out;
  const double beta = spec.helix_angle, alpha_n = spec.pressure_angle;
  const double alpha_t = std::atan(std::tan(alpha_n) / std::cos(beta));
  const double beta_b = std::atan(std::tan(beta) * std::cos(alpha_t));
  std::array<double, 2> zn{};
  for (int i = 0; i < 2; ++i)
    zn[i] = spec.teeth[i] / (std::cos(beta) * std::cos(beta_b) * std::cos(beta_b));
  const double x1 = spec.profile_shift[0], x2 = spec.profile_shift[1];
  // q' [mm um/N] with C1..C9 of ISO 6336-1 method B (python-gearbox iso.py; Drivetrain Gear_Set.m
  // has C9 x1^2 where the standard has C9 x2^2).
  const double q = 0.04723 + 0.15551 / zn[0] + 0.25791 / zn[1] - 0.00635 * x1 -
                   0.11654 * x1 / zn[0] - 0.00193 * x2 - 0.24188 * x2 / zn[1] + 0.00529 * x1 * x1 +
                   0.00182 * x2 * x2;
  const double c_th = 1.0 / q;  // N/(mm um)
  out.c_m = 0.8;                // solid disc gears
  out.c_r = 1.0;                // solid gear blanks
  out.c_b = (1.0 + 0.5 * (1.2 - spec.tool_dedendum_coefficient)) *
            (1.0 - 0.02 * (20.0 - alpha_n * 180.0 / kPi));
  const double e_ratio = spec.material.youngs_modulus / 2.06e11;  // E / E_st, E_st = 206 000 N/mm^2
  const double c_prime = c_th * out.c_m * out.c_r * out.c_b * std::cos(beta) * e_ratio;
  // Transverse contact ratio of the transverse section (spur: the geometry itself).
  GearPairSpec transverse = spec;
  transverse.helix_angle = 0.0;
  transverse.module = spec.module / std::cos(beta);
  transverse.pressure_angle = alpha_t;
  for (int i = 0; i < 2; ++i) transverse.profile_shift[i] = spec.profile_shift[i] * std::cos(beta);
  transverse.addendum_coefficient = spec.addendum_coefficient * std::cos(beta);
  transverse.tool_dedendum_coefficient = spec.tool_dedendum_coefficient * std::cos(beta);
  if (spec.center_distance) transverse.center_distance = spec.center_distance;
  out.transverse_contact_ratio = SpurGearGeometry(transverse).contactRatio();
  double c_gamma = c_prime * (0.75 * out.transverse_contact_ratio + 0.25);
  if (out.transverse_contact_ratio < 1.2) c_gamma *= 0.9;
  out.single_stiffness_theoretical = c_th * 1e9;
  out.single_stiffness = c_prime * 1e9;
  out.mesh_stiffness = c_gamma * 1e9;
  out.mesh_stiffness_helical = 0.85 * c_gamma * 1e9;
  return out;
}

std::unique_ptr<ToothPairStiffness> makeToothPairStiffness(MeshStiffnessModel model,
                                                           const SpurGearGeometry& geometry,
                                                           double face_width) {
  requirePositive("gears.face_width", face_width);
  switch (model) {
    case MeshStiffnessModel::kPotentialEnergy:
      return std::make_unique<PotentialEnergyModel>(geometry, face_width);
    case MeshStiffnessModel::kKuangYang:
      return std::make_unique<KuangYangModel>(geometry, face_width);
    case MeshStiffnessModel::kIso6336: return std::make_unique<Iso6336Model>(geometry, face_width);
  }
  throw InvalidInput("mesh stiffness model: unknown");
}

MeshStiffnessTable::MeshStiffnessTable(const SpurGearGeometry& geometry,
                                       const ToothPairStiffness& model, int samples)
    : geometry_(geometry) {
  if (samples < 2 || samples > 1000000) throwInvalid("samples", samples, "must be in [2, 1e6]");
  s0_ = geometry.pathStart();
  const double step = (geometry.pathEnd() - s0_) / (samples - 1);
  inv_step_ = 1.0 / step;
  values_.resize(samples);
  for (int i = 0; i < samples; ++i)
    values_[i] = model.pairStiffness(geometry.contactAt(s0_ + i * step));
}

double MeshStiffnessTable::pair(double s) const {
  const double u = std::clamp((s - s0_) * inv_step_, 0.0, static_cast<double>(values_.size() - 1));
  const std::size_t i = std::min(static_cast<std::size_t>(u), values_.size() - 2);
  const double w = u - static_cast<double>(i);
  return values_[i] + w * (values_[i + 1] - values_[i]);
}

double MeshStiffnessTable::drive(double phase) const {
  std::array<double, 3> s;
  const int n = geometry_.drivePairs(phase, s);
  double k = 0.0;
  for (int i = 0; i < n; ++i) k += pair(s[i]);
  return k;
}

}  // namespace drivetrain_stiffness

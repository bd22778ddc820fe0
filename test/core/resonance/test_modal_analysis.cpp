// Modal analysis and Floquet stability against closed forms and the Mathieu equation.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

using namespace drivetrain_stiffness;

namespace {
GearRotorParameters seedParameters() {  // seed 000 Table 1 masses and inertias
  GearRotorParameters p;
  p.pinion_mass = 33.95e-3;
  p.gear_mass = 48.27e-3;
  p.pinion_inertia = 0.0515e-6;
  p.gear_inertia = 0.258e-6;
  p.pinion_base_radius = 0.3e-3 * 20 * std::cos(20 * M_PI / 180);
  p.gear_base_radius = 0.3e-3 * 40 * std::cos(20 * M_PI / 180);
  p.bearing_stiffness = {1.0e8, 1.3e8};
  return p;
}
}  // namespace

// Without mesh stiffness each shaft is a single-DOF oscillator: f = sqrt(k/m)/2pi and
// zeta = c / (2 sqrt(k m)); the torsional coordinate is free (0 Hz).
TEST(ModalAnalysis, DecoupledLimit) {
  GearRotorParameters p = seedParameters();
  p.bearing_damping = {2 * 0.03 * std::sqrt(1.0e8 * 33.95e-3),
                       2 * 0.05 * std::sqrt(1.3e8 * 48.27e-3)};
  const auto modes = modalAnalysis(p, 0.0);
  EXPECT_NEAR(modes[0].natural_frequency, 0.0, 1e-3);
  EXPECT_EQ(modes[0].dominant, "x");
  const double f_p = std::sqrt(1.0e8 / 33.95e-3) / (2 * M_PI),
               f_g = std::sqrt(1.3e8 / 48.27e-3) / (2 * M_PI);
  // Sorted: gear shaft (8.26 kHz) below pinion shaft (8.64 kHz).
  EXPECT_NEAR(modes[1].natural_frequency / std::min(f_p, f_g), 1.0, 1e-9);
  EXPECT_NEAR(modes[2].natural_frequency / std::max(f_p, f_g), 1.0, 1e-9);
  EXPECT_EQ(modes[1].dominant, "x_g");
  EXPECT_NEAR(modes[1].damping_ratio, 0.05, 1e-9);
  EXPECT_NEAR(modes[2].damping_ratio, 0.03, 1e-9);
  EXPECT_NEAR(modes[2].damped_frequency / (modes[2].natural_frequency * std::sqrt(1 - 0.03 * 0.03)),
              1.0, 1e-9);
}

// Coupled: each mode satisfies K v = w^2 M v, and sum w_i^2 = trace(M^-1 K) (a solver-free check).
TEST(ModalAnalysis, CoupledSeedModes) {
  const GearRotorParameters p = seedParameters();
  const double ks = 1.28e8;
  const auto modes = modalAnalysis(p, ks);
  const Eigen::Vector3d mass(p.pinion_mass, p.gear_mass, p.equivalentMass());
  Eigen::Matrix3d k;
  k << 1.0e8 + ks, -ks, ks, -ks, 1.3e8 + ks, -ks, ks, -ks, ks;
  double sum = 0.0;
  for (const Mode& m : modes) {
    const double w2 = std::pow(2 * M_PI * m.natural_frequency, 2);
    EXPECT_LT((k * m.shape - w2 * mass.asDiagonal() * m.shape).norm(),
              1e-6 * w2 * (mass.asDiagonal() * m.shape).norm());
    sum += w2;
  }
  EXPECT_NEAR(sum / (mass.cwiseInverse().asDiagonal() * k).trace(), 1.0, 1e-12);
  // The torsional mode near 60 kHz (docs/model.md), dominated by x; the shafts near 8-9 kHz.
  EXPECT_EQ(modes[2].dominant, "x");
  EXPECT_NEAR(modes[2].natural_frequency, 60e3, 8e3);
  EXPECT_LT(modes[1].natural_frequency, 12e3);
}

namespace {
// x'' + k(t) x = 0 with k = 1 + eps cos(W t) on a unit equivalent mass (r = 1, I = 2); the shafts
// are heavy, stiff and damped so that their own multipliers sit well inside the unit circle.
class MathieuExcitation : public GearExcitation {
 public:
  MathieuExcitation(double w, double eps) : w_(w), eps_(eps) {}
  void at(double t, MeshInstant& out) const override {
    out.k_drive = 1.0 + eps_ * std::cos(w_ * t);
    out.k_back = 0.0;
    out.preload_force = 0.0;
    out.backlash = 0.0;  // an ordinary gear without backlash: both flanks together a linear spring
    out.drive_force = 0.0;
  }
  double nextSwitch(double) const override { return INFINITY; }

 private:
  double w_, eps_;
};

// Linearise in contact (delta > 0): at delta = 0 a zero-backlash gear sits on its dead-zone edge,
// where the contact counts as open.
State6 inContact() {
  State6 y = State6::Zero();
  y[2] = 1e-6;
  return y;
}

GearRotorModel mathieuModel(double w, double eps) {
  GearRotorParameters p;
  p.pinion_mass = p.gear_mass = 1e6;
  p.bearing_stiffness = {1e6, 1e6};
  p.bearing_damping = {2e5, 2e5};
  p.pinion_inertia = p.gear_inertia = 2.0;
  p.pinion_base_radius = p.gear_base_radius = 1.0;
  return GearRotorModel(p, std::make_shared<MathieuExcitation>(w, eps));
}
}  // namespace

// Mathieu equation x'' + (a - 2q cos 2tau) x = 0: the first instability tongue is a = 1 -/+ q to
// first order (Abramowitz & Stegun 20.2.25). With tau = W t / 2: a = 4/W^2, q = -2 eps / W^2, so
// the undamped system is unstable for W in (2 sqrt(1 - eps/2), 2 sqrt(1 + eps/2)) = (1.949, 2.049)
// at eps = 0.1 (second-order corrections ~3e-4). Points 0.02 inside and outside the tongue:
TEST(Floquet, MathieuFirstTongue) {
  const double eps = 0.1;
  for (double w : {1.93, 1.97, 2.03, 2.07}) {
    const GearRotorModel model = mathieuModel(w, eps);
    const FloquetResult r = floquet(model, inContact(), 0.0, 2 * M_PI / w, 4000);
    const bool inside = w > 2 * std::sqrt(1 - eps / 2) && w < 2 * std::sqrt(1 + eps / 2);
    if (inside) {
      EXPECT_GT(r.max_modulus, 1.01) << w;
      EXPECT_LT(r.margin, 0.0) << w;
    } else {
      // Stable: not growing, and within 1e-4 of the unit circle (x itself is undamped; the heavy
      // damped shafts drain a little energy through the mesh coupling).
      EXPECT_LE(r.max_modulus, 1.0 + 1e-9) << w;
      EXPECT_GT(r.max_modulus, 1.0 - 1e-4) << w;
    }
  }
}

// Brute force: inside the tongue the free response grows by max|mu| per period.
TEST(Floquet, AgreesWithDirectIntegration) {
  const double w = 2.0, eps = 0.1, period = 2 * M_PI / w;
  const GearRotorModel model = mathieuModel(w, eps);
  const FloquetResult r = floquet(model, inContact(), 0.0, period, 4000);
  State6 y = State6::Zero();
  y[2] = 1e-3;
  IntegratorOptions o;
  o.relative_tolerance = 1e-11;
  o.absolute_tolerance = 1e-14;
  o.max_step = 0.05;
  o.divergence_limit = 1e3;
  const int n = 40;
  double peak_early = 0.0, peak_late = 0.0;
  integrate(model, IntegratorMethod::kDopri5, o, 0.0, y, n * period, period / 100,
            [&](double t, const State6& s) {
              if (t < 2 * period) peak_early = std::max(peak_early, std::abs(s[2]));
              if (t >= (n - 2) * period) peak_late = std::max(peak_late, std::abs(s[2]));
            });
  const double growth_per_period = std::pow(peak_late / peak_early, 1.0 / (n - 2));
  EXPECT_NEAR(growth_per_period, r.max_modulus, 0.01 * r.max_modulus);
}

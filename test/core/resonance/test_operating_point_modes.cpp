// The modes of a configured rig at an operating point (operating_point_modes.hpp), the numbers of
// `drivetrain_cli modes`, against independent sources: the ISO 6336-1 step of the mesh stiffness,
// the 3-DOF eigenproblem assembled here from Newton's law, the mesh frequency of the kinematics,
// and Liouville's formula for the Floquet multipliers.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/gear/mesh_stiffness.hpp"
#include "drivetrain_stiffness/core/resonance/operating_point_modes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

using namespace drivetrain_stiffness;

namespace {
RigConfig rigFile(const std::string& relative) {
  return loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/" + relative);
}

// Seed 000 Table 1 (config/gearboxes/seed_servo.yaml): m = 0.6 mm, z = 20 / 40, alpha = 20 deg,
// h_a = 1, masses and inertias; speed 1000 rpm; damping ratios 0.05 (mesh) and 0.02 (bearings).
constexpr double kModule = 0.6e-3, kMp = 33.95e-3, kMg = 48.27e-3, kIp = 0.0515e-6, kIg = 0.258e-6;
const double kAlpha = 20.0 * M_PI / 180.0;
const double kRbp = kModule * 20 / 2 * std::cos(kAlpha),
             kRbg = kModule * 40 / 2 * std::cos(kAlpha);  // r_b = m z cos(alpha) / 2
// Seed 000 eq 14: the torsional coordinate x = r_p theta_p - r_g theta_g carries m_s = 1 /
// (r_p^2/I_p + r_g^2/I_g).
const double kMs = 1.0 / (kRbp * kRbp / kIp + kRbg * kRbg / kIg);

// ISO 21771 transverse contact ratio of a standard spur pair at the standard centre distance:
// eps = [sqrt(ra1^2 - rb1^2) + sqrt(ra2^2 - rb2^2) - a sin(alpha)] / (pi m cos(alpha)).
double contactRatio() {
  const double r1 = kModule * 10, r2 = kModule * 20, ra1 = r1 + kModule, ra2 = r2 + kModule;
  return (std::sqrt(ra1 * ra1 - kRbp * kRbp) + std::sqrt(ra2 * ra2 - kRbg * kRbg) -
          (r1 + r2) * std::sin(kAlpha)) /
         (M_PI * kModule * std::cos(kAlpha));
}

// Newton's second law for (x_p, x_g, x) with delta = x + x_p - x_g (seed 000 eqs 15-18): the mesh
// force k delta acts on x_p and x with +, on x_g with -; each bearing holds its shaft.
Eigen::Matrix3d stiffnessMatrix(double k, double kp, double kg) {
  Eigen::Matrix3d m;
  m << k + kp, -k, k, -k, k + kg, -k, k, -k, k;
  return m;
}
}  // namespace

// ISO 6336-1 method B gives each tooth pair the constant stiffness c_gamma_alpha b / eps_alpha
// (mesh_stiffness.hpp), so over a mesh period an ordinary gear's mesh stiffness steps between one
// pair (the minimum) and two pairs (the maximum, twice it): c_gamma_alpha = c' (0.75 eps + 0.25)
// (ISO 6336-1:2019 eq. 9.2; our c' matches ISO/TR 6336-30 example 1 in test_mesh_stiffness.cpp).
TEST(OperatingPointModes, MeshRangeIsOneAndTwoIsoPairs) {
  RigConfig rig = rigFile("test/data/ordinary_servo.yaml");
  rig.mesh_model = MeshStiffnessModel::kIso6336;
  const AntiBacklashMesh mesh(rig);
  const Iso6336Stiffness iso = iso6336Stiffness(rig.gears);
  const double eps = contactRatio();
  ASSERT_NEAR(eps, 1.635, 1e-3);  // docs/gear_model.md section 2: the seed pair's contact ratio
  const double pair = iso.single_stiffness * (0.75 * eps + 0.25) * 6.5e-3 / eps;
  const MeshStiffnessRange r = meshStiffnessRange(mesh, 0.1 / kRbp);
  EXPECT_NEAR(r.min / pair, 1.0, 1e-6);
  EXPECT_NEAR(r.max / (2.0 * pair), 1.0, 1e-6);
  // One sample lands in the single-pair zone only if that zone (2 - eps of the period) is wider
  // than a sample.
  EXPECT_NEAR(meshStiffnessRange(mesh, 0.1 / kRbp, 1).max / (2.0 * pair), 1.0,
              1e-6);  // phase 0.5: two pairs
  EXPECT_THROW(meshStiffnessRange(mesh, 0.0, 0), InvalidInput);
}

// The seed rig at its Table 1 torque: the natural frequencies at the mean, single- and double-pair
// mesh stiffness are the roots of det(K - w^2 M) = 0 with K and M assembled here.
TEST(OperatingPointModes, SeedRigModesSolveTheEigenproblem) {
  const OperatingPointModes r =
      operatingPointModes(rigFile("config/gearboxes/seed_servo.yaml"), 0.1);
  EXPECT_NEAR(r.parameters.equivalentMass() / kMs, 1.0, 1e-12);
  // Both shafts carry the same bearing, preloads and the same |mesh force|: the same stiffness.
  EXPECT_NEAR(r.bearing_stiffness[0] / r.bearing_stiffness[1], 1.0, 1e-12);
  EXPECT_GT(r.bearing_stiffness[0], 1e7);
  EXPECT_LT(r.mesh_range.min, r.mesh_mean);
  EXPECT_LT(r.mesh_mean, r.mesh_range.max);
  const Eigen::Matrix3d mass = Eigen::Vector3d(kMp, kMg, kMs).asDiagonal();
  const std::pair<double, const std::array<Mode, 3>*> cases[] = {
      {r.mesh_mean, &r.modes_mean},
      {r.mesh_range.min, &r.modes_single_pair},
      {r.mesh_range.max, &r.modes_double_pair}};
  for (const auto& [k, modes] : cases) {
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d> eig(
        stiffnessMatrix(k, r.bearing_stiffness[0], r.bearing_stiffness[1]), mass);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR((*modes)[i].natural_frequency / (std::sqrt(eig.eigenvalues()[i]) / (2 * M_PI)),
                  1.0, 1e-9)
          << k << " mode " << i;
    }
  }
}

// Floquet over one mesh period T = 60 / (z_p n). Liouville's formula: the product of the
// multipliers is det Phi(T) = exp(integral of tr A) = exp(-T tr(M^-1 C)), the trace of the damping
// alone whatever the stiffness does over the period; C from the damping ratios of the dynamics
// block, c_s = 2 zeta_s sqrt(k_mean m_s), c_b = 2 zeta_b sqrt(k_b m) (docs/model.md). At the seed's
// 1000 rpm the mesh mode (61 kHz, zeta 0.05) decays by e^-57 over a period, below the round-off of
// the monodromy's eigenvalues, so the product is checked at 20000 rpm (e^-2.9).
TEST(OperatingPointModes, FloquetMultipliersObeyLiouville) {
  RigConfig rig = rigFile("config/gearboxes/seed_servo.yaml");
  const OperatingPointModes seed = operatingPointModes(rig, 0.1);
  ASSERT_TRUE(seed.floquet.has_value());
  EXPECT_NEAR(seed.floquet->mesh_frequency, 20 * 1000.0 / 60.0, 1e-9);
  EXPECT_GT(seed.floquet->result.margin, 0.0);  // stable: damped, no parametric resonance at 333 Hz
  rig.dynamics.speed_rpm = 20000.0;
  const OperatingPointModes r = operatingPointModes(rig, 0.1);
  ASSERT_TRUE(r.floquet.has_value());
  EXPECT_NEAR(r.floquet->mesh_frequency, 20 * 20000.0 / 60.0, 1e-9);
  const double period = 60.0 / (20 * 20000.0);
  const double cs = 2 * 0.05 * std::sqrt(r.mesh_mean * kMs);
  const double cp = 2 * 0.02 * std::sqrt(r.bearing_stiffness[0] * kMp),
               cg = 2 * 0.02 * std::sqrt(r.bearing_stiffness[1] * kMg);
  const double trace = (cs + cp) / kMp + (cs + cg) / kMg + cs / kMs;
  double product = 1.0, largest = 0.0;
  for (int i = 0; i < 6; ++i) {
    product *= std::abs(r.floquet->result.multipliers[i]);
    largest = std::max(largest, std::abs(r.floquet->result.multipliers[i]));
  }
  // Measured 1.8e-6 with the table's exact period mean (1.5e-7 with a 256-sample mean; the damping
  // agrees with the model's to all digits, so the difference is the propagators' rounding, not yet
  // understood): bounded at 1e-5.
  EXPECT_NEAR(std::log(product) / (-period * trace), 1.0, 1e-5);
  EXPECT_DOUBLE_EQ(r.floquet->result.max_modulus, largest);
  EXPECT_DOUBLE_EQ(r.floquet->result.margin, 1.0 - largest);
  EXPECT_GT(r.floquet->result.margin, 0.0);
}

// With a radial bearing clearance the model has no linear regime: modes, but no Floquet margin.
TEST(OperatingPointModes, NoFloquetWithBearingClearance) {
  RigConfig rig = rigFile("config/gearboxes/seed_servo.yaml");
  rig.dynamics.bearing_clearance = {1e-6, 0.0};
  const OperatingPointModes r = operatingPointModes(rig, 0.1);
  EXPECT_FALSE(r.floquet.has_value());
  EXPECT_GT(r.modes_mean[0].natural_frequency, 0.0);
}

TEST(OperatingPointModes, RefusesWhatItCannotAnalyse) {
  RigConfig rig = rigFile("config/gearboxes/seed_servo.yaml");
  EXPECT_THROW(operatingPointModes(rig, NAN), InvalidInput);
  rig.dynamics.present = false;
  EXPECT_THROW(operatingPointModes(rig, 0.1), InvalidInput);
}

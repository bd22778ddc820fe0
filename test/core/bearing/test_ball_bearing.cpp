// One bearing: geometry, the analytic force and tangent against finite differences, and the
// closed forms under pure axial load (bearing.md section 3).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "bearing_fixtures.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

using namespace drivetrain_stiffness;

TEST(BallBearing, GeometryFollowsSeed003) {
  const BallBearing b(test::acbb7013());
  EXPECT_NEAR(b.grooveCentreDistance(), (0.515 + 0.515 - 1.0) * 11.1e-3, 1e-15);  // seed 003 eq 1
  // seed 003 eq 3 inverted: the free contact angle given must come back from the clearance.
  EXPECT_NEAR(std::acos(1.0 - b.unmountedClearance() / (2.0 * b.grooveCentreDistance())),
              25.0 * M_PI / 180.0, 1e-12);
  EXPECT_NEAR(b.freeContactAngle(), 25.0 * M_PI / 180.0, 1e-12);
  // seed 003 eq 8: R_i = d_m/2 + (r_i - D/2) cos(alpha0)
  EXPECT_NEAR(b.innerGrooveCentreRadius(),
              82.5e-3 / 2 + (5.7165e-3 - 5.55e-3) * std::cos(25.0 * M_PI / 180.0), 1e-12);
}

// The inner-ring fit reduces the clearance by the Lame raceway growth and so lowers the contact
// angle (seed 000 eq 10); the outer fit likewise.
TEST(BallBearing, InterferenceReducesClearanceAndContactAngle) {
  const BallBearing free(test::acbb7013());
  const BallBearing fitted(test::acbb7013(), Interference{10e-6, 10e-6});
  EXPECT_NEAR(fitted.mountedClearance(),
              free.mountedClearance() - fitted.innerRacewayGrowth() - fitted.outerRacewayShrink(),
              1e-18);
  EXPECT_GT(fitted.innerRacewayGrowth(), 0.0);
  EXPECT_LT(fitted.freeContactAngle(), free.freeContactAngle());
}

// The force is the gradient of the stored energy and the tangent is the gradient of the force:
// central differences at random states with partial contact (some balls unloaded).
TEST(BallBearing, AnalyticForceAndTangentMatchFiniteDifferences) {
  const BallBearing b(test::acbb7013());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double uz0 = b.axialDisplacementForLoad(1500.0);
  for (int trial = 0; trial < 20; ++trial) {
    Vector5d q;
    q << 8e-6 * u(rng), 8e-6 * u(rng), uz0 + 4e-6 * u(rng), 2e-4 * u(rng), 2e-4 * u(rng);
    const BearingEvaluation e = b.evaluate(q);
    Vector5d h;
    h << 1e-9, 1e-9, 1e-9, 1e-8, 1e-8;
    for (int i = 0; i < 5; ++i) {
      Vector5d dq = Vector5d::Zero();
      dq[i] = h[i];
      const BearingEvaluation ep = b.evaluate(q + dq), em = b.evaluate(q - dq);
      const double force_fd = (ep.energy - em.energy) / (2.0 * h[i]);
      EXPECT_NEAR(force_fd, e.force[i],
                  1e-5 * e.force.cwiseAbs().maxCoeff() * (i >= 3 ? 0.05 : 1.0))
          << trial << "," << i;
      const Vector5d column_fd = (ep.force - em.force) / (2.0 * h[i]);
      const double scale = e.stiffness.col(i).cwiseAbs().maxCoeff();
      for (int j = 0; j < 5; ++j)
        EXPECT_NEAR(column_fd[j], e.stiffness(j, i), 1e-5 * scale) << trial << "," << i << "," << j;
    }
    // A Hessian of a convex energy: symmetric, positive semi-definite.
    EXPECT_LT((e.stiffness - e.stiffness.transpose()).cwiseAbs().maxCoeff(),
              1e-9 * e.stiffness.cwiseAbs().maxCoeff());
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix5d>(e.stiffness).eigenvalues().minCoeff(),
              -1e-9 * e.stiffness.cwiseAbs().maxCoeff());
  }
}

// Closed forms under pure axial load (bearing.md section 3, derived; Harris & Kotzalas give the
// thrust equation Fa = Z Kn A^1.5 sin(a) (cos(a0)/cos(a) - 1)^1.5):
//   ka = Z Kn d^0.5 (1.5 sin^2 a + e cos^2 a), kr = (Z/2) Kn d^0.5 (1.5 cos^2 a + e sin^2 a),
//   k_theta = R_i^2 ka / 2, e = d / L.
TEST(BallBearing, PureAxialLoadMatchesClosedForms) {
  const BallBearing b(test::acbb7013());
  const double a0 = b.freeContactAngle(), big_a = b.grooveCentreDistance(),
               kn = b.loadDeflectionConstant();
  for (double fa : {200.0, 1000.0, 3000.0}) {
    const double uz = b.axialDisplacementForLoad(fa);
    const double ar = big_a * std::cos(a0);
    const double l = std::hypot(ar, uz), delta = l - big_a, eps = delta / l,
                 alpha = std::atan2(uz, ar);
    const double z = 19;
    EXPECT_NEAR(z * kn * std::pow(big_a, 1.5) * std::sin(alpha) *
                    std::pow(std::cos(a0) / std::cos(alpha) - 1.0, 1.5) / fa,
                1.0, 1e-10);
    Vector5d q = Vector5d::Zero();
    q[kUz] = uz;
    const BearingEvaluation e = b.evaluate(q);
    EXPECT_NEAR(e.force[kUz] / fa, 1.0, 1e-10);
    const double s2 = std::sin(alpha) * std::sin(alpha), c2 = std::cos(alpha) * std::cos(alpha);
    const double ka = z * kn * std::sqrt(delta) * (1.5 * s2 + eps * c2);
    const double kr = z / 2.0 * kn * std::sqrt(delta) * (1.5 * c2 + eps * s2);
    const double ri = b.innerGrooveCentreRadius();
    EXPECT_NEAR(e.stiffness(kUz, kUz) / ka, 1.0, 1e-10);
    EXPECT_NEAR(e.stiffness(kUx, kUx) / kr, 1.0, 1e-10);
    EXPECT_NEAR(e.stiffness(kUy, kUy) / kr, 1.0, 1e-10);  // axisymmetric
    EXPECT_NEAR(e.stiffness(kThetaX, kThetaX) / (ri * ri * ka / 2.0), 1.0, 1e-10);
    EXPECT_NEAR(e.stiffness(kThetaY, kThetaY) / (ri * ri * ka / 2.0), 1.0, 1e-10);
    EXPECT_LT(std::abs(e.stiffness(kUx, kUy)), 1e-9 * kr);
  }
}

// Inside the clearance no ball touches: zero force, zero stiffness, nothing non-finite.
TEST(BallBearing, InsideClearanceIsForceAndStiffnessFree) {
  const BallBearing b(test::deepGroove(12, 20e-6));
  for (double ux : {0.0, 4e-6, -9e-6}) {
    Vector5d q = Vector5d::Zero();
    q[kUx] = ux;
    const BearingEvaluation e = b.evaluate(q);
    EXPECT_EQ(e.force.norm(), 0.0);
    EXPECT_EQ(e.stiffness.norm(), 0.0);
    for (const BallState& s : b.balls(q)) {
      EXPECT_FALSE(s.in_contact);
      EXPECT_TRUE(std::isfinite(s.contact_angle));
    }
  }
  EXPECT_NEAR(b.axialDisplacementForLoad(0.0),  // half the axial play: sqrt(A^2 - (A - Pd/2)^2)
              std::sqrt(std::pow(b.grooveCentreDistance(), 2) -
                        std::pow(b.grooveCentreDistance() - 10e-6, 2)),
              1e-15);
}

TEST(BallBearing, RejectsBadSpecsNamingTheField) {
  auto expectMessage = [](BallBearingSpec s, const std::string& text, Interference i = {}) {
    try {
      BallBearing b(s, i);
      FAIL() << "accepted: " << text;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  auto s = test::acbb7013();
  s.balls = 2;
  expectMessage(s, "balls = 2");
  s = test::acbb7013();
  s.ball_diameter = -1e-3;
  expectMessage(s, "ball_diameter = -0.001");
  s = test::acbb7013();
  s.ball_diameter = NAN;
  expectMessage(s, "ball_diameter = nan");
  s = test::acbb7013();
  s.inner_groove_conformity = 0.5;
  expectMessage(s, "inner_groove_conformity = 0.5");
  s = test::acbb7013();
  s.balls = 30;
  expectMessage(s, "do not fit");
  s = test::acbb7013();
  s.contact_angle.reset();
  s.diametral_clearance = 1e-3;
  expectMessage(s, "diametral_clearance = 0.001");
  s = test::acbb7013();
  s.diametral_clearance = 1e-5;
  expectMessage(s, "exactly one of");
  s = test::acbb7013();
  s.material.poisson_ratio = 0.7;
  expectMessage(s, "poisson_ratio = 0.7");
  s = test::acbb7013();
  s.fit.reset();
  expectMessage(s, "needs the fit geometry", {5e-6, 0.0});
  expectMessage(test::acbb7013(), "outer_interference = -1e-06", {0.0, -1e-6});
}

// Mesh-order removal: a sinusoid following a measured angle, with varying amplitude, sweeping
// near and through the modes of records with exactly known poles (synthetic_modes.hpp).
#include <cmath>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/modal/order_removal.hpp"
#include "synthetic_modes.hpp"

namespace drivetrain_stiffness::modal {
namespace {

using test::rigModes;
using test::SyntheticModes;

constexpr double kFs = 51200.0;

/// Mesh angle [rad] of a linear sweep from f0 to f1 [Hz] over the samples: 2 pi (f0 t + (f1 -
/// f0) t^2 / 2T).
Eigen::VectorXd sweepAngle(long samples, double f0, double f1) {
  Eigen::VectorXd a(samples);
  const double duration = samples / kFs;
  for (long t = 0; t < samples; ++t) {
    const double s = t / kFs;
    a[t] = 2.0 * M_PI * (f0 * s + 0.5 * (f1 - f0) * s * s / duration);
  }
  return a;
}

/// Orders 1, 2 and 3 of the angle with amplitudes `amplitude` x (1, 0.5, 0.25), modulated by
/// 1 + 0.5 sin(2 pi t), on channel weights (1, 0.7).
Eigen::MatrixXd meshOrders(const Eigen::VectorXd& angle, double amplitude) {
  Eigen::MatrixXd m(2, angle.size());
  for (long t = 0; t < angle.size(); ++t) {
    const double am = 1.0 + 0.5 * std::sin(2.0 * M_PI * t / kFs);
    const double x = amplitude * am *
                     (std::cos(angle[t] + 0.3) + 0.5 * std::sin(2.0 * angle[t]) +
                      0.25 * std::cos(3.0 * angle[t] - 1.0));
    m(0, t) = x;
    m(1, t) = 0.7 * x;
  }
  return m;
}

double rms(const Eigen::MatrixXd& x) { return std::sqrt(x.squaredNorm() / x.size()); }

OrderRemoval meshRemoval() {
  OrderRemovalOptions o;
  o.orders = {1.0, 2.0, 3.0};
  return OrderRemoval(o);
}

TEST(OrderRemoval, RemovesASweepingOrderWithVaryingAmplitude) {
  const long n = 51200;
  const Eigen::MatrixXd clean = rigModes().record(n, 31);
  const Eigen::VectorXd angle = sweepAngle(n, 7000.0, 10000.0);
  const Eigen::MatrixXd mesh = meshOrders(angle, 5.0 * rms(clean));
  // Alone: what is left is the amplitude's change within a block, at most 0.5 x 2 pi x 1 Hz x
  // 20 ms = 6.3 % of the amplitude, which the fit's constant amplitude leaves as a ramp of rms
  // 6.3 % / sqrt(12) = 1.8 %.
  Eigen::MatrixXd alone = mesh;
  meshRemoval().remove(alone, angle, kFs);
  EXPECT_LT(rms(alone), 0.018 * rms(mesh)) << rms(alone) / rms(mesh);
  // With the modes: also their response projected on the regressors (6 of 1024 per block, more
  // where the sweep crosses a mode).
  Eigen::MatrixXd y = clean + mesh;
  meshRemoval().remove(y, angle, kFs);
  EXPECT_LT(rms(y - clean), 0.15 * rms(clean)) << rms(y - clean) / rms(clean);
}

TEST(OrderRemoval, ASweepThroughAModeIsNeverReportedAsAMode) {
  const long n = 51200;
  const SyntheticModes sys = rigModes();
  const Eigen::MatrixXd clean = sys.record(n, 32);
  const Eigen::VectorXd angle = sweepAngle(n, 7600.0, 8200.0);  // through 7.9 kHz
  Eigen::MatrixXd y = clean + meshOrders(angle, 5.0 * rms(clean));
  const OrderRemoval removal = meshRemoval();
  removal.remove(y, angle, kFs);
  const std::vector<FrequencyBand> bands = removal.bands(angle, kFs);
  SsiOptions o;
  o.max_order = 40;
  const SelectionResult sel = selectModes(SsiCov(o).identify(y, kFs), bands);
  for (const IdentifiedMode& m : sel.modes)
    for (const FrequencyBand& b : bands)
      EXPECT_FALSE(m.frequency >= b.low && m.frequency <= b.high)
          << m.frequency << " Hz reported inside " << b.label;
  // The 9.4 kHz mode, outside the bands, is found.
  const double f1 = std::abs(sys.pole(1)) / (2.0 * M_PI);
  int found = 0;
  for (const IdentifiedMode& m : sel.modes) found += std::abs(m.frequency - f1) < 0.002 * f1;
  EXPECT_EQ(found, 1);
}

TEST(OrderRemoval, ASweepBesideTheModesLeavesExactlyTheTwoModes) {
  const long n = 51200;
  const SyntheticModes sys = rigModes();
  const Eigen::MatrixXd clean = sys.record(n, 33);
  const Eigen::VectorXd angle = sweepAngle(n, 8400.0, 8800.0);  // between the modes
  Eigen::MatrixXd y = clean + meshOrders(angle, 5.0 * rms(clean));
  const OrderRemoval removal = meshRemoval();
  removal.remove(y, angle, kFs);
  SsiOptions o;
  o.max_order = 40;
  const SelectionResult sel = selectModes(SsiCov(o).identify(y, kFs), removal.bands(angle, kFs));
  ASSERT_EQ(sel.modes.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const double f = std::abs(sys.pole(k)) / (2.0 * M_PI);
    EXPECT_NEAR(sel.modes[k].frequency, f, 0.002 * f);
  }
}

TEST(OrderRemoval, BandsFollowTheRateAndFoldAboveNyquist) {
  const long n = 8192;
  OrderRemovalOptions o;
  o.orders = {1.0, 3.0};
  o.band_margin = 0.0;
  const OrderRemoval removal(o);
  const Eigen::VectorXd angle = sweepAngle(n, 10000.0, 10000.0);  // constant 10 kHz
  const std::vector<FrequencyBand> bands = removal.bands(angle, kFs);
  ASSERT_EQ(bands.size(), 2u);
  const double resolution = kFs / 1024.0;
  // Order 3 at 30 kHz aliases to 51.2 - 30 = 21.2 kHz.
  EXPECT_NEAR(bands[0].low, 10000.0 - resolution, 1e-6);
  EXPECT_NEAR(bands[0].high, 10000.0 + resolution, 1e-6);
  EXPECT_NEAR(bands[1].low, 21200.0 - resolution, 1e-6);
  EXPECT_NEAR(bands[1].high, 21200.0 + resolution, 1e-6);
  EXPECT_EQ(bands[1].label, "order 3");
}

TEST(OrderRemoval, RejectsBadArgumentsNamingTheField) {
  auto expectInvalid = [](const std::function<void()>& f, const std::string& text) {
    try {
      f();
      ADD_FAILURE() << "no InvalidInput for " << text;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  OrderRemovalOptions o;
  o.orders = {1.0, -2.0};
  expectInvalid([&] { OrderRemoval{o}; }, "order_removal.orders[1] = -2");
  o.orders = {1.0};
  o.block_samples = 8;
  expectInvalid([&] { OrderRemoval{o}; }, "order_removal.block_samples = 8");
  const OrderRemoval removal = meshRemoval();
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(2, 4096);
  Eigen::VectorXd angle = Eigen::VectorXd::Zero(4000);
  expectInvalid([&] { removal.remove(y, angle, kFs); }, "angle.size = 4000");
  angle = Eigen::VectorXd::Zero(4096);
  angle[17] = std::nan("");
  expectInvalid([&] { removal.remove(y, angle, kFs); }, "angle[17] = nan");
  expectInvalid([&] { removal.bands(angle.head(100), kFs); }, "record.samples = 100");
  expectInvalid([&] { removal.bands(angle, -1.0); }, "sample_rate = -1");
}

TEST(SynchronousAverage, RemovesEveryHarmonicOfTheCycleAndKeepsTheRest) {
  // 30 harmonics of a 333.3 Hz mesh (to 10 kHz, each 1/k of the first) following a speed that
  // drifts by 2 % over 4 s, on the rig's two modes (white-noise driven). The synchronous average
  // over the mesh cycles removes the harmonics (linear in the samples), and leaves the modes'
  // response, which is not periodic in the angle. The average is linear in the record, so the
  // two parts are checked on their own.
  const long n = 4 * 51200;
  const Eigen::MatrixXd modes = rigModes(kFs).record(n, 21, 0.05);
  const Eigen::VectorXd cycles = sweepAngle(n, 333.3, 340.0) / (2.0 * M_PI);
  Eigen::MatrixXd harmonics(2, n);
  for (long t = 0; t < n; ++t) {
    double x = 0.0;
    for (int k = 1; k <= 30; ++k) x += std::cos(2.0 * M_PI * k * cycles[t] + 0.1 * k) / k;
    harmonics(0, t) = x;
    harmonics(1, t) = -0.7 * x;
  }
  Eigen::MatrixXd y = harmonics;
  removeSynchronousAverage(y, cycles, 12800);
  const double left = rms(y) / rms(harmonics);
  EXPECT_LT(left, 0.02) << "of the harmonics' rms left";
  y = modes;
  removeSynchronousAverage(y, cycles, 12800);
  // The modes' own mean over the m samples of a bin goes with it: at most 1/m of their power
  // (bins of 2 per sample of a cycle: m = 12800 / (2 x 12800 / 83 cycles) = 41.5), less where
  // the interpolation mixes two bins' means.
  const double kept = rms(y) / rms(modes);
  EXPECT_GT(kept, std::sqrt(1.0 - 1.0 / 41.5) - 0.002);
  EXPECT_LT(kept, 1.0);
}

TEST(SynchronousAverage, RejectsBadArgumentsNamingTheField) {
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(2, 100);
  Eigen::VectorXd cycles = Eigen::VectorXd::LinSpaced(100, 0.0, 20.0);
  EXPECT_THROW(removeSynchronousAverage(y, cycles.head(99), 32), InvalidInput);
  EXPECT_THROW(removeSynchronousAverage(y, cycles, 8), InvalidInput);
  cycles[7] = NAN;
  try {
    removeSynchronousAverage(y, cycles, 32);
    FAIL() << "a NaN cycle was taken";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("cycles[7]"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace drivetrain_stiffness::modal

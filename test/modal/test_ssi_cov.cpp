// SsiCov against records with exactly known poles (synthetic_modes.hpp) and its standard
// deviations against the scatter of independent records.
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/modal/ssi_cov.hpp"
#include "synthetic_modes.hpp"

namespace drivetrain_stiffness::modal {
namespace {

using test::rigModes;
using test::SyntheticModes;

double macReal(const Eigen::VectorXcd& a, const Eigen::VectorXd& b) {
  const std::complex<double> ab = a.dot(b.cast<std::complex<double>>());
  return std::norm(ab) / (a.squaredNorm() * b.squaredNorm());
}

/// The pole of order n nearest to f (nullptr if none within 2 %).
const Pole* nearest(const SsiResult& r, int n, double f) {
  const Pole* best = nullptr;
  for (const Pole& p : r.poles)
    if (p.order == n && std::abs(p.frequency - f) < 0.02 * f &&
        (!best || std::abs(p.frequency - f) < std::abs(best->frequency - f)))
      best = &p;
  return best;
}

TEST(SsiCov, IdentifiesTwoModesOfAOneSecondRecord) {
  const SyntheticModes sys = rigModes();
  const Eigen::MatrixXd y = sys.record(51200, 1);
  SsiOptions o;
  o.max_order = 20;
  const SsiResult r = SsiCov(o).identify(y, sys.sampleRate());
  EXPECT_EQ(r.channels, 2);
  EXPECT_EQ(r.variance_blocks, 50);
  for (int k = 0; k < 2; ++k) {
    const std::complex<double> lc = sys.pole(k);
    const double f = std::abs(lc) / (2.0 * M_PI), z = -lc.real() / std::abs(lc);
    for (int n = 4; n <= 20; n += 2) {
      const Pole* p = nearest(r, n, f);
      ASSERT_NE(p, nullptr) << "mode " << k << " order " << n;
      EXPECT_NEAR(p->frequency, f, 0.002 * f) << "order " << n;
      // Damping: within 4 of its own std and 25 % (a 1 s record holds ~160 decay times).
      EXPECT_NEAR(p->damping, z, 4.0 * p->damping_std) << "order " << n;
      EXPECT_NEAR(p->damping, z, 0.25 * z) << "order " << n;
      EXPECT_GT(p->frequency_std, 0.0);
      EXPECT_GT(macReal(p->shape, sys.shapes().col(k)), 0.99) << "order " << n;
    }
  }
}

// At the true order (4: two modes), where the first-order propagation's assumption of a clear
// singular-value gap holds (docs/vibration.md, "Variance propagation").
TEST(SsiCov, StandardDeviationsMatchTheScatterOfIndependentRecords) {
  const SyntheticModes sys = rigModes();
  SsiOptions o;
  o.min_order = 4;
  o.max_order = 4;
  o.variance_blocks = 40;
  const SsiCov ssi(o);
  const int runs = 80;
  const long samples = 12800;  // 0.25 s
  for (int k = 0; k < 2; ++k) {
    const std::complex<double> lc = sys.pole(k);
    const double f0 = std::abs(lc) / (2.0 * M_PI);
    std::vector<double> f, z;
    double pf = 0.0, pz = 0.0;
    for (int run = 0; run < runs; ++run) {
      const SsiResult r = ssi.identify(sys.record(samples, 1000 + run), sys.sampleRate());
      const Pole* p = nearest(r, 4, f0);
      ASSERT_NE(p, nullptr) << "run " << run;
      f.push_back(p->frequency);
      z.push_back(p->damping);
      pf += p->frequency_std * p->frequency_std / runs;
      pz += p->damping_std * p->damping_std / runs;
    }
    auto stddev = [](const std::vector<double>& x) {
      double m = 0.0, v = 0.0;
      for (double e : x) m += e / x.size();
      for (double e : x) v += (e - m) * (e - m) / (x.size() - 1);
      return std::sqrt(v);
    };
    const double rf = std::sqrt(pf) / stddev(f), rz = std::sqrt(pz) / stddev(z);
    EXPECT_GT(rf, 0.7) << "mode " << k;
    EXPECT_LT(rf, 1.4) << "mode " << k;
    EXPECT_GT(rz, 0.7) << "mode " << k;
    EXPECT_LT(rz, 1.4) << "mode " << k;
    std::printf("mode %d: predicted/observed std  frequency %.3f  damping %.3f\n", k, rf, rz);
  }
}

TEST(SsiCov, WithoutVarianceBlocksTheStdIsNaN) {
  const SyntheticModes sys = rigModes();
  SsiOptions o;
  o.max_order = 8;
  o.variance_blocks = 0;
  const SsiResult r = SsiCov(o).identify(sys.record(8192, 3), sys.sampleRate());
  const Pole* p = nearest(r, 8, 7900.0);
  ASSERT_NE(p, nullptr);
  EXPECT_TRUE(std::isnan(p->frequency_std));
  EXPECT_EQ(r.variance_blocks, 0);
}

/// White noise of `rms` through a moving average of `taps` samples: correlated at lags below
/// `taps` only (an MA(taps - 1) process), as an anti-alias FIR correlates a sensor's noise.
Eigen::MatrixXd movingAverageNoise(long channels, long samples, int taps, double rms,
                                   unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd w(channels, samples + taps - 1);
  for (long c = 0; c < channels; ++c)
    for (long t = 0; t < w.cols(); ++t) w(c, t) = g(rng);
  Eigen::MatrixXd n(channels, samples);
  for (long t = 0; t < samples; ++t) n.col(t) = w.middleCols(t, taps).rowwise().sum();
  return n * (rms / std::sqrt(static_cast<double>(taps)));
}

// R_k = C A^(k-1) G holds for lags past the noise's correlation (Van Overschee & De Moor 1996,
// Ch. 3: the stochastic realization assumes white noise): an MA noise biases the poles through the
// lags it correlates, and a Hankel that starts past them identifies the modes within their std.
TEST(SsiCov, SkippedLagsRemoveTheBiasOfCorrelatedNoise) {
  const SyntheticModes sys = rigModes();
  const int taps = 12;
  const int runs = 8;
  SsiOptions o;
  o.min_order = 8;  // two modes and room for the noise's colour
  o.max_order = 8;
  o.block_rows = 20;
  for (int skipped : {0, taps}) {
    o.skipped_lags = skipped;
    std::array<double, 2> mean_z{0.0, 0.0};
    for (int run = 0; run < runs; ++run) {
      Eigen::MatrixXd y = sys.record(51200, 300 + run, 0.0);
      const double rms = std::sqrt(y.squaredNorm() / y.size());
      y += movingAverageNoise(2, y.cols(), taps, 2.0 * rms, 700 + run);
      const SsiResult r = SsiCov(o).identify(y, sys.sampleRate());
      EXPECT_EQ(r.skipped_lags, skipped);
      for (int k = 0; k < 2; ++k) {
        const double f = std::abs(sys.pole(k)) / (2.0 * M_PI);
        const Pole* p = nearest(r, 8, f);
        ASSERT_NE(p, nullptr) << "skipped " << skipped << " run " << run << " mode " << k;
        mean_z[k] += (p->frequency - f) / p->frequency_std / runs;
      }
    }
    for (int k = 0; k < 2; ++k) {
      std::printf("skipped lags %d, mode %d: mean (f - f_true) / std over %d records %.2f\n",
                  skipped, k, runs, mean_z[k]);
      // The mean of 8 standard normal scores has std 0.35: unbiased within 3 of it.
      if (skipped >= taps) {
        EXPECT_LT(std::abs(mean_z[k]), 1.05) << "mode " << k;
      }
    }
    if (skipped == 0) {  // the bias the skipped lags remove: over 4 std of the mean
      EXPECT_GT(std::max(std::abs(mean_z[0]), std::abs(mean_z[1])), 1.5);
    }
  }
}

void expectInvalid(const std::function<void()>& f, const std::string& text) {
  try {
    f();
    ADD_FAILURE() << "no InvalidInput for " << text;
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

TEST(SsiCov, RejectsBadOptionsAndRecordsNamingTheField) {
  SsiOptions o;
  o.min_order = 3;
  expectInvalid([&] { SsiCov{o}; }, "ssi.min_order = 3");
  o = {};
  o.max_order = 41;
  expectInvalid([&] { SsiCov{o}; }, "ssi.max_order = 41");
  o = {};
  o.variance_blocks = 1;
  expectInvalid([&] { SsiCov{o}; }, "ssi.variance_blocks = 1");
  o = {};
  o.skipped_lags = -1;
  expectInvalid([&] { SsiCov{o}; }, "ssi.skipped_lags = -1");
  o = {};
  o.block_rows = 5;  // (5 - 1) * 2 = 8 < 40
  const Eigen::MatrixXd y = rigModes().record(20000, 4);
  expectInvalid([&] { SsiCov(o).identify(y, 51200.0); }, "ssi.block_rows = 5");
  const SsiCov ssi;
  expectInvalid([&] { ssi.identify(Eigen::MatrixXd(0, 100), 51200.0); }, "record.channels = 0");
  expectInvalid([&] { ssi.identify(y, 0.0); }, "sample_rate = 0");
  expectInvalid([&] { ssi.identify(y.leftCols(500), 51200.0); }, "record.samples = 500");
  expectInvalid([&] { ssi.identify(Eigen::MatrixXd::Constant(2, 20000, 3.0), 51200.0); },
                "record.rms = 0");
  Eigen::MatrixXd bad = y;
  bad(1, 7) = std::nan("");
  expectInvalid([&] { ssi.identify(bad, 51200.0); }, "record(1, 7) = nan");
}

}  // namespace
}  // namespace drivetrain_stiffness::modal

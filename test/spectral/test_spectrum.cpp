// Spectra and peaks against synthetic signals whose answer is known.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/spectral/sliding_spectrum.hpp"
#include "drivetrain_stiffness/spectral/spectrum.hpp"

using namespace drivetrain_stiffness;

// Two sines between bins: both found, strongest first, frequencies within 0.05 bin and amplitudes
// within 2 % after the log-parabola refinement (the Hann window's scalloping alone would be 15 %).
TEST(Spectrum, FindsTwoOffBinSines) {
  const double dt = 1e-4, n = 4096;
  const double df = 1.0 / (n * dt);  // 2.44 Hz
  const double f1 = 103.3 * df, f2 = 250.7 * df, a1 = 2.0, a2 = 0.5;
  std::vector<double> x;
  for (int i = 0; i < n; ++i)
    x.push_back(3.0 + a1 * std::sin(2 * M_PI * f1 * i * dt) +
                a2 * std::cos(2 * M_PI * f2 * i * dt));
  const Spectrum s = amplitudeSpectrum(x, dt);
  EXPECT_NEAR(s.resolution, df, 1e-12);
  const auto peaks = topPeaks(s, 3);
  ASSERT_GE(peaks.size(), 2u);
  EXPECT_NEAR(peaks[0].frequency, f1, 0.05 * df);
  EXPECT_NEAR(peaks[1].frequency, f2, 0.05 * df);
  EXPECT_NEAR(peaks[0].amplitude / a1, 1.0, 0.02);
  EXPECT_NEAR(peaks[1].amplitude / a2, 1.0, 0.02);
}

TEST(Spectrum, CurvePeaksOfAResonanceCurve) {
  // |H(f)| of a damped oscillator sampled every 50 Hz: the peak at f_n sqrt(1 - 2 zeta^2) within
  // a fifth of the step.
  const double fn = 1234.0, zeta = 0.05;
  std::vector<double> f, h;
  for (double v = 500; v <= 2000; v += 50) {
    const double r = v / fn;
    f.push_back(v);
    h.push_back(1.0 / std::sqrt((1 - r * r) * (1 - r * r) + (2 * zeta * r) * (2 * zeta * r)));
  }
  const auto p = curvePeaks(f, h, 1);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NEAR(p[0].frequency, fn * std::sqrt(1 - 2 * zeta * zeta), 10.0);
}

TEST(Spectrum, RejectsBadSignals) {
  EXPECT_THROW(amplitudeSpectrum({1, 2, 3}, 1e-3), InvalidInput);
  std::vector<double> x(64, 0.0);
  x[5] = NAN;
  EXPECT_THROW(amplitudeSpectrum(x, 1e-3), InvalidInput);
  EXPECT_THROW(amplitudeSpectrum(std::vector<double>(64, 0.0), 0.0), InvalidInput);
}

// Sliding window: the first peaks appear after a full window, then every hop; a sine that changes
// frequency is followed once the window has slid past the change.
TEST(SlidingSpectrum, FollowsTheLatestWindow) {
  const double dt = 1e-3;
  SlidingSpectrum s(1024, 256, dt, 2);
  EXPECT_NEAR(s.resolution(), 1.0 / 1.024, 1e-12);
  int updates = 0;
  for (int i = 0; i < 2048; ++i) {
    const double f = i < 1024 ? 100.3 : 333.3;
    updates += s.push(1e-6 * std::sin(2 * M_PI * f * i * dt));
    if (i == 1023) {
      ASSERT_FALSE(s.peaks().empty());
      EXPECT_NEAR(s.peaks()[0].frequency, 100.3, 0.05 * s.resolution());
    }
  }
  EXPECT_EQ(updates, 5);  // at 1024, 1280, 1536, 1792, 2048 samples
  EXPECT_NEAR(s.peaks()[0].frequency, 333.3, 0.05 * s.resolution());
  EXPECT_NEAR(s.peaks()[0].amplitude, 1e-6, 0.02e-6);
  EXPECT_THROW(s.push(NAN), InvalidInput);
  EXPECT_THROW(SlidingSpectrum(4, 1, dt), InvalidInput);
  EXPECT_THROW(SlidingSpectrum(64, 65, dt), InvalidInput);
}

// The analyzer plans once and is reused (the node's sliding spectrum): each result equals a fresh
// amplitudeSpectrum of the same samples, bit for bit, whatever came before; and analyzers can be
// built on several threads at once (FFTW's planner is not thread-safe; they share one lock).
TEST(SpectrumAnalyzer, ReusedPlanEqualsAFreshSpectrumAndPlansOnManyThreads) {
  const int n = 256;
  const double dt = 1e-3;
  drivetrain_stiffness::SpectrumAnalyzer analyzer(n, dt);
  for (double f : {50.0, 123.0, 333.3}) {
    std::vector<double> x(n);
    for (int i = 0; i < n; ++i) x[i] = std::sin(2 * M_PI * f * i * dt) + 0.1 * std::cos(0.37 * i);
    const drivetrain_stiffness::Spectrum fresh = drivetrain_stiffness::amplitudeSpectrum(x, dt);
    const drivetrain_stiffness::Spectrum& reused = analyzer.compute(x);
    ASSERT_EQ(reused.amplitude.size(), fresh.amplitude.size());
    for (std::size_t k = 0; k < fresh.amplitude.size(); ++k)
      EXPECT_EQ(reused.amplitude[k], fresh.amplitude[k]) << f << " " << k;
  }
  EXPECT_THROW(analyzer.compute(std::vector<double>(n - 1, 0.0)),
               drivetrain_stiffness::InvalidInput);
  std::vector<std::thread> threads;
  std::atomic<int> good{0};
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&good, t] {
      for (int i = 0; i < 20; ++i) {
        drivetrain_stiffness::SpectrumAnalyzer a(64 + 8 * t, 1e-3);
        std::vector<double> x(64 + 8 * t, 0.0);
        x[3] = 1.0;
        if (std::isfinite(a.compute(x).amplitude[1])) ++good;
      }
    });
  }
  for (std::thread& th : threads) th.join();
  EXPECT_EQ(good.load(), 160);
}

// Automatic pole selection on records with exactly known poles (synthetic_modes.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/modal/pole_selection.hpp"
#include "synthetic_modes.hpp"

namespace drivetrain_stiffness::modal {
namespace {

using test::rigModes;
using test::SyntheticModes;

Eigen::VectorXcd complexShape(const Eigen::VectorXd& v) { return v.cast<std::complex<double>>(); }

double trueFrequency(const SyntheticModes& s, int k) { return std::abs(s.pole(k)) / (2.0 * M_PI); }
double trueDamping(const SyntheticModes& s, int k) {
  return -s.pole(k).real() / std::abs(s.pole(k));
}

TEST(PoleSelection, MacOfKnownVectors) {
  Eigen::VectorXcd a(2), b(2);
  a << 1.0, 0.0;
  b << 0.0, 1.0;
  EXPECT_DOUBLE_EQ(mac(a, b), 0.0);
  EXPECT_DOUBLE_EQ(mac(a, a), 1.0);
  b << 1.0, 1.0;
  EXPECT_NEAR(mac(a, b), 0.5, 1e-15);                                   // cos^2 45 deg
  EXPECT_NEAR(mac(a, b * std::complex<double>(0.0, 3.0)), 0.5, 1e-15);  // scale-free
  EXPECT_THROW(mac(a, Eigen::VectorXcd::Ones(3)), InvalidInput);
}

TEST(PoleSelection, FindsExactlyTheTwoModesOfAOneSecondRecord) {
  const SyntheticModes sys = rigModes();
  SsiOptions o;
  o.max_order = 40;
  const SsiResult ssi = SsiCov(o).identify(sys.record(51200, 11), sys.sampleRate());
  const SelectionResult sel = selectModes(ssi);
  ASSERT_EQ(sel.modes.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const IdentifiedMode& m = sel.modes[k];
    EXPECT_NEAR(m.frequency, trueFrequency(sys, k), 0.002 * trueFrequency(sys, k));
    EXPECT_NEAR(m.frequency, trueFrequency(sys, k), 4.0 * m.frequency_std);
    EXPECT_NEAR(m.damping, trueDamping(sys, k), 4.0 * m.damping_std);
    EXPECT_GT(mac(m.shape, complexShape(sys.shapes().col(k))), 0.99);
    EXPECT_FALSE(m.unresolved);
    EXPECT_GE(m.orders, 12);  // of 20 orders
  }
}

// The representative's std (the cluster member with the smallest std) against the scatter of
// the representatives of independent records.
TEST(PoleSelection, RepresentativeStdMatchesTheScatterOfIndependentRecords) {
  const SyntheticModes sys = rigModes();
  SsiOptions o;
  o.max_order = 20;
  o.variance_blocks = 40;
  const SsiCov ssi(o);
  const int runs = 60;
  std::vector<std::vector<double>> f(2), z(2);
  std::vector<double> pf(2, 0.0), pz(2, 0.0);
  for (int run = 0; run < runs; ++run) {
    const SelectionResult sel =
        selectModes(ssi.identify(sys.record(12800, 2000 + run), sys.sampleRate()));
    ASSERT_EQ(sel.modes.size(), 2u) << "run " << run;
    for (int k = 0; k < 2; ++k) {
      f[k].push_back(sel.modes[k].frequency);
      z[k].push_back(sel.modes[k].damping);
      pf[k] += std::pow(sel.modes[k].frequency_std, 2) / runs;
      pz[k] += std::pow(sel.modes[k].damping_std, 2) / runs;
    }
  }
  auto stddev = [](const std::vector<double>& x) {
    double m = 0.0, v = 0.0;
    for (double e : x) m += e / x.size();
    for (double e : x) v += (e - m) * (e - m) / (x.size() - 1);
    return std::sqrt(v);
  };
  for (int k = 0; k < 2; ++k) {
    const double rf = std::sqrt(pf[k]) / stddev(f[k]), rz = std::sqrt(pz[k]) / stddev(z[k]);
    std::printf("mode %d: predicted/observed std  frequency %.3f  damping %.3f\n", k, rf, rz);
    EXPECT_GT(rf, 0.7);
    EXPECT_LT(rf, 1.4);
    EXPECT_GT(rz, 0.7);
    EXPECT_LT(rz, 1.4);
  }
}

TEST(PoleSelection, WhiteNoiseHasNoMode) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd y(2, 51200);
  for (long t = 0; t < y.cols(); ++t) y(0, t) = g(rng), y(1, t) = g(rng);
  SsiOptions o;
  o.max_order = 40;
  const SelectionResult sel = selectModes(SsiCov(o).identify(y, 51200.0));
  EXPECT_TRUE(sel.modes.empty()) << sel.modes.size() << " modes, first at "
                                 << sel.modes.front().frequency << " Hz";
}

// Two modes 2.5 % apart (7.9 and 8.1 kHz) with distinct shapes over the two channels.
TEST(PoleSelection, SeparatesTwoCloseModes) {
  Eigen::MatrixXd shapes(2, 2);
  shapes << 1.0, 0.3, 0.4, -1.0;
  const SyntheticModes sys({{7900.0, 0.01}, {8100.0, 0.01}}, shapes, 51200.0);
  SsiOptions o;
  o.max_order = 40;
  const SsiResult ssi = SsiCov(o).identify(sys.record(51200, 21), sys.sampleRate());
  const SelectionResult sel = selectModes(ssi);
  ASSERT_EQ(sel.modes.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(sel.modes[k].frequency, trueFrequency(sys, k), 0.002 * trueFrequency(sys, k));
    EXPECT_GT(mac(sel.modes[k].shape, complexShape(shapes.col(k))), 0.98);
    EXPECT_FALSE(sel.modes[k].unresolved);
  }
}

// The same two modes with one channel: their shapes are the same scalar and the two modes
// cannot be told apart by shape; no mode may then be reported as resolved at a frequency its own
// 2-std band does not put on a true mode (its std says how far apart the wandering poles are).
TEST(PoleSelection, CloseModesOnOneChannelAreNeverResolvedWrongly) {
  Eigen::MatrixXd shapes(1, 2);
  shapes << 1.0, 1.0;
  const SyntheticModes sys({{7900.0, 0.01}, {8100.0, 0.01}}, shapes, 51200.0);
  SsiOptions o;
  o.max_order = 40;
  const SsiResult ssi = SsiCov(o).identify(sys.record(51200, 22), sys.sampleRate());
  const SelectionResult sel = selectModes(ssi);
  for (const IdentifiedMode& m : sel.modes) {
    if (m.unresolved) continue;
    const double error = std::min(std::abs(m.frequency - trueFrequency(sys, 0)),
                                  std::abs(m.frequency - trueFrequency(sys, 1)));
    EXPECT_LT(error, std::max(0.002 * m.frequency, 2.0 * m.frequency_std))
        << m.frequency << " +- " << m.frequency_std << " Hz";
  }
}

// A mode's frequency must be known within its own resonance: a stable, damped cluster whose std
// exceeds half its half-power half-width (damping x frequency) is noise, not a mode.
TEST(PoleSelection, AClusterWhoseFrequencyIsNotResolvedWithinItsResonanceIsSpurious) {
  auto cluster = [](double frequency_std) {
    SsiResult r;
    r.min_order = 4;
    r.max_order = 20;
    r.channels = 2;
    r.variance_blocks = 50;
    for (int n = 4; n <= 20; n += 2) {
      Pole p;
      p.order = n;
      p.frequency = 9600.0;
      p.damping = 0.03;  // half-power half-width 288 Hz
      p.frequency_std = frequency_std;
      p.damping_std = 0.002;  // damping significant: 15 std
      p.shape = Eigen::VectorXcd::Ones(2);
      r.poles.push_back(p);
    }
    return selectModes(r, {}).modes.size();
  };
  EXPECT_EQ(cluster(20.0), 1u);
  EXPECT_EQ(cluster(143.0), 1u);  // 0.5 x 288 Hz = 144 Hz
  EXPECT_EQ(cluster(145.0), 0u);
}

TEST(PoleSelection, RejectsThresholdsOutOfRange) {
  const SsiResult empty;
  SelectionOptions o;
  o.max_damping = 0.0;
  try {
    selectModes(empty, {}, o);
    ADD_FAILURE();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("selection.max_damping = 0"), std::string::npos);
  }
  o = {};
  o.stable_mac = 1.5;
  EXPECT_THROW(selectModes(empty, {}, o), InvalidInput);
  o = {};
  o.frequency_resolution = 0.0;
  EXPECT_THROW(selectModes(empty, {}, o), InvalidInput);
  FrequencyBand nan_band;
  nan_band.low = std::nan("");
  EXPECT_THROW(selectModes(empty, {nan_band}), InvalidInput);
}

}  // namespace
}  // namespace drivetrain_stiffness::modal

// TeSpectrumStage: every hop once its window is full the sink gets the sliding window's own lines
// (against a SlidingSpectrum fed the same samples), a restart empties the window, and a
// non-finite TE is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/pipeline/te_spectrum_stage.hpp"
#include "seed_rig.hpp"  // NOLINT(build/include_subdir)

using namespace drivetrain_stiffness;

namespace {

struct Spectra : PipelineSink {
  std::vector<SpectrumPeaks> out;
  std::vector<Stamp> stamps;
  void spectrum(Stamp stamp, const SpectrumPeaks& p) override {
    out.push_back(p);
    stamps.push_back(stamp);
  }
};

constexpr double kDt = 1e-3;  // [s]
double te(int k) {
  return 1e-6 * std::sin(kTwoPi * 125.0 * k * kDt) + 3e-7 * std::sin(kTwoPi * 250.0 * k * kDt);
}

void feed(TeSpectrumStage& stage, Spectra& sink, int from, int to) {
  for (int k = from; k < to; ++k) {
    DynamicsSample s;
    s.dynamic_te = te(k);
    stage.sample(test::stampAt(k * kDt), s, 0.0, sink);
  }
}

}  // namespace

TEST(TeSpectrumStage, EveryHopTheWindowsOwnLines) {
  TeSpectrumStage stage(64, 16, kDt);
  SlidingSpectrum reference(64, 16, kDt, SpectrumPeaks::kMaxPeaks);
  Spectra sink;
  std::vector<std::vector<SpectralPeak>> expected;
  for (int k = 0; k < 128; ++k) {
    if (reference.push(te(k))) expected.push_back(reference.peaks());
  }
  feed(stage, sink, 0, 128);
  ASSERT_EQ(sink.out.size(), 5u);  // at 64, 80, 96, 112 and 128 samples
  ASSERT_EQ(expected.size(), sink.out.size());
  EXPECT_EQ(stage.counters().spectra_out, 5u);
  EXPECT_TRUE(sink.stamps[0] == test::stampAt(63 * kDt));  // the newest sample in the window
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(sink.out[i].count, expected[i].size());
    for (std::size_t j = 0; j < sink.out[i].count; ++j) {
      EXPECT_EQ(sink.out[i].peaks[j].frequency, expected[i][j].frequency);
      EXPECT_EQ(sink.out[i].peaks[j].amplitude, expected[i][j].amplitude);
    }
    EXPECT_DOUBLE_EQ(sink.out[i].window_seconds, 64 * kDt);
    EXPECT_DOUBLE_EQ(sink.out[i].resolution, 1.0 / (64 * kDt));
  }
  EXPECT_NEAR(sink.out[0].peaks[0].frequency, 125.0, sink.out[0].resolution);
}

TEST(TeSpectrumStage, ARestartEmptiesTheWindow) {
  TeSpectrumStage stage(64, 16, kDt);
  Spectra sink;
  feed(stage, sink, 0, 60);
  stage.restart();
  feed(stage, sink, 60, 123);  // 63 samples since the restart: one short of a window
  EXPECT_TRUE(sink.out.empty());
  feed(stage, sink, 123, 124);
  EXPECT_EQ(sink.out.size(), 1u);
}

TEST(TeSpectrumStage, ANonFiniteTeIsRefused) {
  TeSpectrumStage stage(64, 16, kDt);
  Spectra sink;
  DynamicsSample s;
  s.dynamic_te = std::nan("");
  EXPECT_THROW(stage.sample(test::stampAt(0.0), s, 0.0, sink), InvalidInput);
}

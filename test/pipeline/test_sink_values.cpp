// What a sink receives is plain values, complete enough that it never needs to ask the pipeline
// back during a callback: the TE spectrum's lines (checked against a SlidingSpectrum fed the same
// samples), the pinion angle and resonance of each sample's moment, and the stiffness bands (the
// drawing's model without a calibration, the calibrator's with one).
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "drivetrain_stiffness/config/yaml_config.hpp"
#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

using namespace drivetrain_stiffness;

namespace {

RigConfig seedServo(bool calibration) {
  RigConfig r =
      loadRigFile(std::string(DRIVETRAIN_SOURCE_DIR) + "/config/gearboxes/seed_servo.yaml");
  r.calibration.present = calibration;
  return r;
}

constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;  // 2026-01-01
Stamp at(double seconds) { return Stamp{kEpoch + std::llround(seconds * 1e9)}; }

struct Recorder : PipelineSink {
  const RigPipeline* pipeline = nullptr;  // read only between inputs, to compare
  std::vector<double> te;
  std::vector<Stamp> te_stamps;
  std::vector<double> angles;
  std::vector<std::optional<double>> resonance_f1;  // first natural frequency seen by each sample
  std::vector<SpectrumPeaks> spectra;
  std::vector<std::pair<StiffnessEstimate, CalibrationBands>> stiffness_out;
  void transmissionError(Stamp stamp, const DynamicsSample& s, const SampleContext& c) override {
    te.push_back(s.dynamic_te);
    te_stamps.push_back(stamp);
    angles.push_back(c.pinion_angle);
    resonance_f1.push_back(c.resonance
                               ? std::optional<double>(c.resonance->modes[0].natural_frequency)
                               : std::nullopt);
  }
  void spectrum(Stamp, const SpectrumPeaks& p) override { spectra.push_back(p); }
  void stiffness(Stamp, const StiffnessEstimate& e, const CalibrationBands& b) override {
    stiffness_out.emplace_back(e, b);
  }
};

}  // namespace

TEST(SinkValues, SpectrumPeaksAreTheSlidingWindowsOwn) {
  PipelineOptions o;
  o.spectrum_window = 64;
  o.spectrum_hop = 16;
  RigPipeline p(seedServo(false), o);
  Recorder r;
  for (int i = 0; i <= 20; ++i)
    ASSERT_EQ(p.torque(at(0.01 * i), 0.1 + 0.02 * (i % 3), r), InputOutcome::kAccepted);
  ASSERT_GE(r.te.size(), 150u);
  // The same samples through a window of the same size: the same lines, bit for bit.
  SlidingSpectrum reference(64, 16, p.dynamics()->outputInterval(), SpectrumPeaks::kMaxPeaks);
  std::size_t k = 0;
  for (double x : r.te) {
    if (!reference.push(x)) continue;
    ASSERT_LT(k, r.spectra.size());
    const SpectrumPeaks& got = r.spectra[k++];
    ASSERT_EQ(got.count, reference.peaks().size());
    for (std::size_t i = 0; i < got.count; ++i) {
      EXPECT_EQ(got.peaks[i].frequency, reference.peaks()[i].frequency);
      EXPECT_EQ(got.peaks[i].amplitude, reference.peaks()[i].amplitude);
    }
    EXPECT_EQ(got.resolution, reference.resolution());
    EXPECT_EQ(got.window_seconds, 64 * p.dynamics()->outputInterval());
  }
  EXPECT_EQ(k, r.spectra.size());
  EXPECT_GE(k, 6u);
}

TEST(SinkValues, EachSampleCarriesThePinionAngleAndResonanceOfItsMoment) {
  RigPipeline p(seedServo(false), PipelineOptions{});
  Recorder r;
  ASSERT_EQ(p.torque(at(0.0), 0.1, r), InputOutcome::kAccepted);
  ASSERT_TRUE(p.lastResonance().has_value());
  ASSERT_EQ(p.torque(at(0.02), 0.1, r), InputOutcome::kAccepted);
  ASSERT_GE(r.te.size(), 19u);
  // Nominal speed (1000 rpm) from the first torque input: angle = omega (t - t0).
  const double omega = 1000.0 * kTwoPi / 60.0;
  for (std::size_t i = 0; i < r.te.size(); ++i) {
    EXPECT_NEAR(r.angles[i], omega * secondsBetween(r.te_stamps[i], at(0.0)), 1e-12) << i;
    ASSERT_TRUE(r.resonance_f1[i].has_value()) << i;
    EXPECT_EQ(*r.resonance_f1[i], p.lastResonance()->modes[0].natural_frequency);
  }
  // A damping change drops the resonance (republished at the next input, after that input's
  // samples): the samples the next input releases carry none, those after it the new one.
  RuntimeSettings changed = p.settings();
  changed.mesh_damping_ratio = changed.mesh_damping_ratio == 0.09 ? 0.08 : 0.09;
  p.apply(changed);
  r.resonance_f1.clear();
  ASSERT_EQ(p.torque(at(0.03), 0.1, r), InputOutcome::kAccepted);
  ASSERT_GE(r.resonance_f1.size(), 9u);
  for (const auto& f : r.resonance_f1) EXPECT_FALSE(f.has_value());
  r.resonance_f1.clear();
  ASSERT_EQ(p.torque(at(0.04), 0.1, r), InputOutcome::kAccepted);
  ASSERT_GE(r.resonance_f1.size(), 9u);
  for (const auto& f : r.resonance_f1) EXPECT_TRUE(f.has_value());
}

TEST(SinkValues, StiffnessBandsAreTheDrawingsWithoutCalibrationAndTheCalibratorsWithIt) {
  {
    RigPipeline p(seedServo(false), PipelineOptions{});
    Recorder r;
    ASSERT_EQ(p.torque(at(0.0), 0.3, r), InputOutcome::kAccepted);
    ASSERT_EQ(r.stiffness_out.size(), 1u);
    const auto& [e, b] = r.stiffness_out[0];
    EXPECT_EQ(b.mesh_stiffness, e.mesh.mean);
    EXPECT_EQ(b.mesh_stiffness_low, e.mesh.mean);
    EXPECT_EQ(b.mesh_stiffness_high, e.mesh.mean);
    EXPECT_TRUE(b.bearing_stiffness == p.estimator().shaftRadialStiffness());
    EXPECT_TRUE(b.bearing_stiffness_low == b.bearing_stiffness &&
                b.bearing_stiffness_high == b.bearing_stiffness);
    EXPECT_FALSE(b.calibrated);
  }
  {
    RigPipeline p(seedServo(true), PipelineOptions{});
    ASSERT_NE(p.calibrator(), nullptr);
    Recorder r;
    ASSERT_EQ(p.torque(at(0.0), 0.3, r), InputOutcome::kAccepted);
    ASSERT_EQ(r.stiffness_out.size(), 1u);
    const CalibrationBands expected = p.calibrator()->bands(0.3, p.estimator(), false);
    const CalibrationBands& b = r.stiffness_out[0].second;
    EXPECT_EQ(b.mesh_stiffness, expected.mesh_stiffness);
    EXPECT_EQ(b.mesh_stiffness_low, expected.mesh_stiffness_low);
    EXPECT_EQ(b.mesh_stiffness_high, expected.mesh_stiffness_high);
    EXPECT_LT(b.mesh_stiffness_low,
              b.mesh_stiffness_high);  // the prior's 95 % band, not zero width
    EXPECT_TRUE(b.bearing_stiffness == expected.bearing_stiffness);
  }
}

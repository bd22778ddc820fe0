// The modal identification stage in the pipeline: synthetic accelerometer records with known
// modes (exactly discretised oscillators, test/modal/synthetic_modes.hpp) through the vibration
// input, a mesh-order line on a mode, and the same bits with and without the worker thread.
#include <cmath>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/pipeline/modal_identification.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"
#include "seed_rig.hpp"
#include "synthetic_modes.hpp"

namespace drivetrain_stiffness {
namespace {

constexpr double kRate = 51200.0;  // [Hz]
constexpr std::size_t kBlock = 1024;

/// Keeps every identification and calibration the pipeline hands out.
struct ModalSink : PipelineSink {
  std::vector<std::pair<Stamp, ModalReport>> reports;
  std::vector<std::pair<Stamp, CalibrationEstimate>> calibrations;
  void modalIdentification(Stamp stamp, const ModalReport& r) override {
    reports.emplace_back(stamp, r);
  }
  void calibration(Stamp stamp, const CalibrationEstimate& e) override {
    calibrations.emplace_back(stamp, e);
  }
};

/// The seed rig's two transverse modes moved (gear 7,800 Hz; pinion at `pinion` Hz), seen by the
/// two housings: each mode mostly on its own shaft's channel.
modal::test::SyntheticModes movedModes(double pinion) {
  Eigen::MatrixXd shapes(2, 2);  // rows: pinion_bearing, gear_bearing; columns: the modes
  shapes << 0.2, 1.0, 1.0, -0.1;
  return modal::test::SyntheticModes({{7800.0, 0.02}, {pinion, 0.02}}, shapes, kRate);
}

/// Feeds `record` (2 x samples) as blocks from t0 [s], with a torque input each block (the
/// nominal phase runs from the first), `line` [m/s^2] added to the pinion channel at mesh
/// harmonic `harmonic` of the nominal mesh phase.
void feed(RigPipeline& pipeline, PipelineSink& sink, const Eigen::MatrixXd& record, double t0,
          double line = 0.0, int harmonic = 0) {
  const std::vector<std::string> channels{"pinion_bearing", "gear_bearing"};
  std::vector<float> data(kBlock * 2);
  const double mesh_hz = 20.0 * 1000.0 / 60.0;  // seed servo: z_p = 20 at 1000 rpm
  for (long first = 0; first + static_cast<long>(kBlock) <= record.cols(); first += kBlock) {
    const double t = t0 + first / kRate;
    ASSERT_EQ(pipeline.torque(test::stampAt(t), 0.5, sink), InputOutcome::kAccepted);
    for (std::size_t i = 0; i < kBlock; ++i) {
      const double ti = (first + static_cast<long>(i)) / kRate;  // since the first torque
      data[2 * i] = static_cast<float>(record(0, first + i) +
                                       line * std::sin(kTwoPi * harmonic * mesh_hz * ti));
      data[2 * i + 1] = static_cast<float>(record(1, first + i));
    }
    const VibrationBlockView block{kRate, channels.data(), 2, data.data(), data.size()};
    ASSERT_EQ(pipeline.vibration(test::stampAt(t), block, sink), InputOutcome::kAccepted);
  }
}

PipelineOptions options(bool worker) {
  PipelineOptions o;
  o.vibration_record = 2.0;
  o.modal_worker = worker;
  o.modal_skipped_lags = 0;  // the synthetic records' noise is white: no filter to skip
  return o;
}

TEST(ModalStage, IdentifiesEachRenewedRecordAndMatchesTheModelModes) {
  RigPipeline pipeline(test::seedServo(), options(false));
  ModalSink sink;
  const Eigen::MatrixXd record = movedModes(9200.0).record(6 * 51200, 7);
  feed(pipeline, sink, record, 10.0);
  pipeline.finish(sink);
  // Three renewed 2 s records in 6 s; the last applied at finish().
  ASSERT_EQ(sink.reports.size(), 3u);
  EXPECT_EQ(pipeline.counters().modal_out, 3u);
  for (const auto& [stamp, r] : sink.reports) {
    EXPECT_EQ(stamp, r.end);
    EXPECT_NEAR(r.duration, 2.0, 1.0 / kRate);
    ASSERT_GE(r.identified[0], 0);  // the model's x_g mode, then x_p
    ASSERT_GE(r.identified[1], 0);
    EXPECT_EQ(r.predicted[0].dominant, "x_g");
    EXPECT_EQ(r.predicted[1].dominant, "x_p");
    const modal::IdentifiedMode& gear = r.modes[r.identified[0]];
    const modal::IdentifiedMode& pinion = r.modes[r.identified[1]];
    // The true poles of the exactly discretised oscillators, within 4 std, and a std that
    // determines a bearing scale (under 1 %). Not the 0.2 % asked of a 20 s record: in a 2 s
    // record a cluster can split into a few low orders (std ~7 Hz) and more higher orders (std
    // 30-100 Hz) whose median the representative follows; the second record's pinion mode is
    // 9,162 +- 63 Hz (-0.41 %, 0.6 std).
    EXPECT_NEAR(gear.frequency, 7800.0, 4.0 * gear.frequency_std);
    EXPECT_NEAR(pinion.frequency, 9200.0, 4.0 * pinion.frequency_std);
    EXPECT_LT(gear.frequency_std, 0.01 * 7800.0);
    EXPECT_LT(pinion.frequency_std, 0.01 * 9200.0);
    EXPECT_EQ(r.observability[2], modal::Observability::kAboveNyquist);  // x at 61 kHz
    const std::string predicts = "where the model predicts " +
                                 std::to_string(std::lround(r.predicted[1].frequency)) +
                                 " Hz (x_p)";
    EXPECT_NE(r.modelStatement(1).find(predicts), std::string::npos) << r.modelStatement(1);
  }
}

TEST(ModalStage, AMeshOrderOnAModeIsRemovedAndNeverReported) {
  // The 28th mesh harmonic at 1000 rpm, 9333.3 Hz, exactly on the pinion mode, as a line of
  // three times the mode's rms.
  const double harmonic_hz = 28 * 20.0 * 1000.0 / 60.0;
  const Eigen::MatrixXd record = movedModes(harmonic_hz).record(4 * 51200, 11);
  const double rms = std::sqrt(record.row(0).squaredNorm() / record.cols());
  RigPipeline pipeline(test::seedServo(), options(false));
  ModalSink sink;
  feed(pipeline, sink, record, 10.0, 3.0 * rms, 28);
  pipeline.finish(sink);
  ASSERT_EQ(sink.reports.size(), 2u);
  for (const auto& [stamp, r] : sink.reports) {
    ASSERT_GE(r.identified[1], 0);
    const modal::IdentifiedMode& pinion = r.modes[r.identified[1]];
    EXPECT_NEAR(pinion.frequency, harmonic_hz, 0.002 * harmonic_hz);
    EXPECT_GT(pinion.damping, 0.01);  // the mode's 0.02, not the line's 0
    for (const modal::IdentifiedMode& m : r.modes) EXPECT_GT(m.damping, 0.002) << m.frequency;
    // The harmonic's band is reported among the removed orders.
    bool listed = false;
    for (const modal::FrequencyBand& b : r.order_bands)
      listed = listed || (b.low <= harmonic_hz && harmonic_hz <= b.high);
    EXPECT_TRUE(listed);
  }
}

TEST(ModalIdentification, ASteadyMeshAverageLeavesTheModesWhereTheyAre) {
  // An average over N mesh cycles takes 1/N of the random response with it, and the residual's
  // lag covariance becomes R(k) - (1/N) sum_d R(k + d P), P the cycle [samples]: terms R(k - P)
  // = R(P - k)^T near k = P, which do not follow C A^(k-1) G when the channels' covariances are
  // not symmetric, as when one input (a rig's mesh force) drives both modes. Here: two modes
  // driven by one white input, no order in the record, 1230 rpm (P = 124.9 samples, beside the
  // Hankel's lags 33-111). Each 10 s record is identified as the pipeline does (orders removed on
  // its steady angle) and again on a still angle (nothing removed: below kMinOrderSpeed).
  // Removing orders that are not there must not move the modes: the mean difference over 6
  // records stays under 0.4 of the modes' std. Averaged over 1 s turn blocks and 0.25 s mesh
  // blocks, as for a varying speed, the modes moved by +1.16 and +0.50 std.
  const modal::test::SyntheticModes modes = modal::test::rigModes(kRate);
  ModalJob job;
  job.sample_rate = kRate;
  job.pinion_teeth = 20;
  job.gear_teeth = 100;
  job.channels = {"pinion_bearing", "gear_bearing"};
  job.channel_shaft = {0, 1};
  const char* names[2] = {"x_g", "x_p"};
  const double truth[2] = {7900.0, 9400.0};  // rigModes' undamped frequencies [Hz]
  for (int k = 0; k < 2; ++k) {
    job.predicted[k].dominant = names[k];
    job.predicted[k].frequency = job.predicted[k].low = job.predicted[k].high = truth[k];
    job.predicted[k].shape << modes.shapes()(0, k), modes.shapes()(1, k), 0.0;
  }
  job.predicted[2].dominant = "x";
  job.predicted[2].frequency = job.predicted[2].low = job.predicted[2].high = 61000.0;
  job.predicted[2].shape << 0.0, 0.0, 1.0;
  const long samples = 10 * static_cast<long>(kRate);
  const double speed = 1230.0 * kTwoPi / 60.0;  // [rad/s]
  const Eigen::VectorXd turning =
      Eigen::VectorXd::LinSpaced(samples, 0.0, speed * (samples - 1) / kRate);
  const Eigen::VectorXd still = Eigen::VectorXd::Zero(samples);
  const int records = 6;
  double shift[2] = {0.0, 0.0};  // sum of (removed - kept) / std
  for (int record = 0; record < records; ++record) {
    job.record = modes.record(samples, 200 + record, 0.05, 2000, true);
    job.angle = turning;
    const ModalReport removed = identifyModes(job);
    job.angle = still;
    const ModalReport kept = identifyModes(job);
    ASSERT_EQ(kept.order_bands.size(), 1u) << "only the flat band's edge: no order removed";
    for (int k = 0; k < 2; ++k) {
      ASSERT_GE(removed.identified[k], 0) << names[k] << ", record " << record;
      ASSERT_GE(kept.identified[k], 0) << names[k] << ", record " << record;
      const modal::IdentifiedMode& a = removed.modes[removed.identified[k]];
      const modal::IdentifiedMode& b = kept.modes[kept.identified[k]];
      shift[k] += (a.frequency - b.frequency) / b.frequency_std;
    }
  }
  for (int k = 0; k < 2; ++k) {
    std::cout << names[k] << ": mean shift " << shift[k] / records << " std\n";
    EXPECT_LT(std::abs(shift[k] / records), 0.4) << names[k];
  }
}

TEST(ModalStage, TheWorkerThreadGivesTheSameBitsAtTheSameInputs) {
  const Eigen::MatrixXd record = movedModes(9200.0).record(5 * 51200, 3);
  RigPipeline deferred(test::seedServo(), options(false));
  RigPipeline worker(test::seedServo(), options(true));
  ModalSink a, b;
  feed(deferred, a, record, 10.0);
  feed(worker, b, record, 10.0);
  // Applied kApplyDelay after each record's end, at the same block either way.
  ASSERT_EQ(a.reports.size(), 2u);
  ASSERT_EQ(b.reports.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(a.reports[k].first, b.reports[k].first);
    ASSERT_EQ(a.reports[k].second.modes.size(), b.reports[k].second.modes.size());
    for (std::size_t i = 0; i < a.reports[k].second.modes.size(); ++i) {
      EXPECT_EQ(a.reports[k].second.modes[i].frequency, b.reports[k].second.modes[i].frequency);
      EXPECT_EQ(a.reports[k].second.modes[i].frequency_std,
                b.reports[k].second.modes[i].frequency_std);
    }
  }
  EXPECT_EQ(a.calibrations.size(), b.calibrations.size());
}

TEST(ModalStage, AResultIsAppliedHalfASecondAfterItsRecord) {
  const Eigen::MatrixXd record = movedModes(9200.0).record(51200 * 13 / 5, 5);  // 2.6 s
  RigPipeline pipeline(test::seedServo(), options(false));
  ModalSink sink;
  feed(pipeline, sink, record, 10.0);
  ASSERT_EQ(sink.reports.size(), 1u);
  // The record ends at 12 s - 1 sample; the first block stamped 0.5 s later (12.5 s) applies it.
  EXPECT_EQ(sink.reports[0].first, sink.reports[0].second.end);
  EXPECT_NEAR(sink.reports[0].second.end.toSec() - test::stampAt(10.0).toSec(), 2.0 - 1 / kRate,
              1e-6);
  pipeline.finish(sink);  // nothing pending
  EXPECT_EQ(sink.reports.size(), 1u);
}

TEST(ModalStage, OffIdentifiesNothing) {
  PipelineOptions o = options(false);
  o.modal_identification = false;
  RigPipeline pipeline(test::seedServo(), o);
  ModalSink sink;
  feed(pipeline, sink, movedModes(9200.0).record(3 * 51200, 1), 10.0);
  pipeline.finish(sink);
  EXPECT_TRUE(sink.reports.empty());
  EXPECT_EQ(pipeline.counters().modal_out, 0u);
}

TEST(ModalStage, OptionsOutOfRangeAreRefusedByName) {
  PipelineOptions o;
  o.modal_max_order = 21;
  EXPECT_THROW(
      {
        try {
          o.validate();
        } catch (const InvalidInput& e) {
          EXPECT_NE(std::string(e.what()).find("modal_max_order"), std::string::npos);
          throw;
        }
      },
      InvalidInput);
  o.modal_max_order = 20;
  o.modal_block_rows = 1;
  EXPECT_THROW(o.validate(), InvalidInput);
  o.modal_block_rows = 40;
  o.modal_skipped_lags = -1;
  try {
    o.validate();
    ADD_FAILURE() << "no InvalidInput for modal_skipped_lags = -1";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("modal_skipped_lags = -1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace drivetrain_stiffness

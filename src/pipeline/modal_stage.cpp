#include "drivetrain_stiffness/pipeline/modal_stage.hpp"

#include <cmath>
#include <utility>

#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"

namespace drivetrain_stiffness {

ModalStage::ModalStage(const RigConfig& rig, const VibrationInput& input, const PhaseSource& phase,
                       const StiffnessEstimator& estimator, CalibrationStage& calibration,
                       const PipelineOptions& options)
    : rig_(rig),
      input_(input),
      phase_(phase),
      estimator_(estimator),
      calibration_(calibration),
      enabled_(options.modal_identification),
      worker_(options.modal_worker),
      max_order_(options.modal_max_order),
      block_rows_(options.modal_block_rows),
      skipped_lags_(options.modal_skipped_lags),
      band_(options.modal_band) {}

ModalStage::~ModalStage() {
  if (pending_.valid()) pending_.wait();
}

void ModalStage::reset() {
  if (pending_.valid()) pending_.wait();
  pending_ = {};
  filled_ = 0;
}

void ModalStage::fill(Stamp stamp, std::size_t first, std::size_t count) {
  // The block is the input record's newest block_frames_ frames. Each frame's angle is the phase
  // source's at the frame's time (the encoders' anchor extrapolated, or the nominal angle: the
  // TE output's rule).
  ModalJob& job = jobs_[filling_];
  const double rate = input_.sampleRate();
  const std::size_t block_first = input_.frames() - block_frames_;
  for (std::size_t j = first; j < first + count; ++j) {
    const auto column = static_cast<Eigen::Index>(filled_++);
    for (std::size_t c = 0; c < input_.columns(); ++c)
      job.record(static_cast<Eigen::Index>(c), column) = input_.value(c, block_first + j);
    const double offset = static_cast<double>(j) * 1e9 / rate;
    job.angle[column] = phase_.pinionAngle(Stamp{stamp.ns + std::llround(offset)});
    if (column == 0) job.start = Stamp{stamp.ns + std::llround(offset)};
  }
}

void ModalStage::afterBlock(Stamp stamp, std::size_t frames, double held_torque,
                            PipelineSink& sink) {
  if (!enabled_) return;
  if (pending_.valid() && !(stamp < apply_at_)) apply(stamp, sink);
  const std::size_t capacity = input_.capacity();
  if (input_.appended() == frames) {
    // A new record (its first block): both buffers sized for it, filled from its start.
    if (pending_.valid()) apply(stamp, sink);
    for (ModalJob& job : jobs_) {
      job.record.resize(static_cast<Eigen::Index>(input_.columns()),
                        static_cast<Eigen::Index>(capacity));
      job.angle.resize(static_cast<Eigen::Index>(capacity));
    }
    filled_ = 0;
  }
  block_frames_ = frames;
  for (std::size_t done = 0; done < frames;) {
    const std::size_t count = std::min(frames - done, capacity - filled_);
    fill(stamp, done, count);
    done += count;
    if (filled_ < capacity) continue;
    if (pending_.valid()) apply(stamp, sink);  // records shorter than kApplyDelay
    start(held_torque);
  }
}

void ModalStage::finish(PipelineSink& sink) {
  if (pending_.valid()) apply(apply_at_, sink);
}

void ModalStage::predict(ModalJob& job, double torque) const {
  // The model's modes at the record's end: the calibrated model's with its 95 % bands when a
  // calibration runs (Calibrator::modes, whose indices its modalUpdate takes), else the
  // estimator's stiffness (ResonanceTracker's model).
  const Calibrator* calibrator = calibration_.calibrator();
  const std::array<Mode, 3> modes =
      calibrator ? calibrator->modes(torque, estimator_)
                 : modalAnalysis(rigRotorParameters(rig_, estimator_.mesh(),
                                                    estimator_.shaftRadialStiffness()),
                                 estimator_.current().mesh.mean);
  const CalibrationBands bands =
      calibrator ? calibrator->bands(torque, estimator_, true) : CalibrationBands{};
  for (std::size_t k = 0; k < 3; ++k) {
    ModelModePrediction& p = job.predicted[k];
    p.dominant = modes[k].dominant;
    p.shape = modes[k].shape;
    p.frequency = calibrator ? bands.natural_frequency[k] : modes[k].natural_frequency;
    p.low = calibrator ? bands.natural_frequency_low[k] : p.frequency;
    p.high = calibrator ? bands.natural_frequency_high[k] : p.frequency;
  }
}

void ModalStage::start(double held_torque) {
  // The filled buffer goes to the identification as it is (no copy); the other is filled next.
  ModalJob& job = jobs_[filling_];
  filling_ = 1 - filling_;
  filled_ = 0;
  const std::size_t columns = input_.columns();
  job.sample_rate = input_.sampleRate();
  job.end = Stamp{job.start.ns +
                  std::llround(static_cast<double>(job.record.cols() - 1) * 1e9 / job.sample_rate)};
  job.torque = held_torque;
  job.channels.clear();
  job.channel_shaft.clear();
  for (std::size_t c = 0; c < columns; ++c) {
    job.channels.push_back(input_.column(c).name);
    job.channel_shaft.push_back(input_.column(c).shaft);
  }
  const auto& teeth = estimator_.mesh().geometry().spec().teeth;
  job.pinion_teeth = teeth[0];
  job.gear_teeth = teeth[1];
  job.max_order = max_order_;
  job.block_rows = block_rows_;
  job.skipped_lags = skipped_lags_;
  job.band = band_;
  predict(job, held_torque);
  apply_at_ = Stamp{job.end.ns + std::llround(kApplyDelay * 1e9)};
  // The last result goes with the new identification and is freed on its thread: its memory is
  // the worker's, and freeing it can return the worker's heap to the system (a millisecond of
  // the callback's time).
  auto identify = [&job, spent = std::move(spent_)]() mutable {
    { const Outcome drop = std::move(spent); }
    Outcome out;
    try {
      out.report = identifyModes(job);
    } catch (const Error& e) {
      out.error = e.what();
    }
    return out;
  };
  // Deferred: run by apply() in the caller's thread, at the same input as the worker's result.
  pending_ = std::async(worker_ ? std::launch::async : std::launch::deferred, std::move(identify));
}

void ModalStage::apply(Stamp stamp, PipelineSink& sink) {
  spent_ = pending_.get();  // freed by the next identification (start())
  const Outcome& outcome = spent_;
  pending_ = {};
  if (!outcome.error.empty()) {
    ++counters_.modal_errors;
    events_.record("modal identification: " + outcome.error);
    return;
  }
  const ModalReport& r = outcome.report;
  try {
    sink.modalIdentification(r.end, r);
    ++counters_.modal_out;
  } catch (const Error& e) {
    ++counters_.modal_errors;
    events_.record(std::string("modal identification: ") + e.what());
  }
  // The matched, resolved frequencies with a standard deviation into the calibration.
  std::array<ModalFrequency, 3> frequencies;
  std::size_t count = 0;
  for (std::size_t i = 0; i < r.modes.size() && count < 3; ++i) {
    const modal::IdentifiedMode& m = r.modes[i];
    const int k = r.model_mode[i];
    if (k < 0 || m.unresolved) continue;  // matching is one to one: model mode k has only i
    if (!(std::isfinite(m.frequency_std) && m.frequency_std > 0.0)) continue;
    frequencies[count++] = {k, m.frequency, m.frequency_std};
  }
  if (count > 0) calibration_.modal(stamp, frequencies.data(), count, r.torque, sink);
}

}  // namespace drivetrain_stiffness

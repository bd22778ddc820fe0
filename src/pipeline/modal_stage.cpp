#include "drivetrain_stiffness/pipeline/modal_stage.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"

namespace drivetrain_stiffness {

ModalStage::ModalStage(const RigConfig& rig, const VibrationInput& input, const PhaseSource& phase,
                       const StiffnessEstimator& estimator, CalibrationStage& calibration,
                       const PipelineOptions& options, PipelineCounters& counters)
    : rig_(rig),
      input_(input),
      phase_(phase),
      estimator_(estimator),
      calibration_(calibration),
      counters_(counters),
      enabled_(options.modal_identification),
      worker_(options.modal_worker),
      max_order_(options.modal_max_order),
      block_rows_(options.modal_block_rows) {}

ModalStage::~ModalStage() {
  if (pending_.valid()) pending_.wait();
}

void ModalStage::reset() {
  if (pending_.valid()) pending_.wait();
  pending_ = {};
  angles_.clear();
  appended_ = renewed_ = 0;
}

void ModalStage::noteAngles(Stamp stamp, std::size_t frames) {
  const std::uint64_t appended = input_.appended();
  if (appended == frames || angles_.size() != input_.capacity()) {  // a new record: its angles
    angles_.assign(input_.capacity(), 0.0);
    renewed_ = 0;
  }
  appended_ = appended;
  renewed_ += frames;
  // The phase source's angle at each frame's time: the encoders' anchor extrapolated, or the
  // nominal angle (the same rule as the TE output's, so both see one angle).
  const double rate = input_.sampleRate();
  const std::size_t capacity = angles_.size();
  for (std::size_t j = 0; j < frames; ++j) {
    const Stamp t{stamp.ns + std::llround(static_cast<double>(j) * 1e9 / rate)};
    angles_[(appended - frames + j) % capacity] = phase_.pinionAngle(t);
  }
}

void ModalStage::afterBlock(Stamp stamp, std::size_t frames, double held_torque,
                            PipelineSink& sink) {
  if (!enabled_) return;
  noteAngles(stamp, frames);
  if (pending_.valid() && !(stamp < apply_at_)) apply(stamp, sink);
  if (renewed_ < input_.capacity() || input_.frames() < input_.capacity()) return;
  if (pending_.valid()) apply(stamp, sink);  // records shorter than kApplyDelay: no overlap
  start(held_torque);
}

void ModalStage::finish(PipelineSink& sink) {
  if (pending_.valid()) apply(apply_at_, sink);
}

void ModalStage::predict(double torque) {
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
    ModelModePrediction& p = job_.predicted[k];
    p.dominant = modes[k].dominant;
    p.shape = modes[k].shape;
    p.frequency = calibrator ? bands.natural_frequency[k] : modes[k].natural_frequency;
    p.low = calibrator ? bands.natural_frequency_low[k] : p.frequency;
    p.high = calibrator ? bands.natural_frequency_high[k] : p.frequency;
  }
}

void ModalStage::start(double held_torque) {
  renewed_ = 0;
  const std::size_t frames = input_.frames(), columns = input_.columns();
  const std::size_t capacity = angles_.size();
  job_.record.resize(static_cast<Eigen::Index>(columns), static_cast<Eigen::Index>(frames));
  job_.angle.resize(static_cast<Eigen::Index>(frames));
  const std::uint64_t first = appended_ - frames;
  for (std::size_t i = 0; i < frames; ++i) {
    for (std::size_t c = 0; c < columns; ++c)
      job_.record(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(i)) = input_.value(c, i);
    job_.angle[static_cast<Eigen::Index>(i)] = angles_[(first + i) % capacity];
  }
  job_.sample_rate = input_.sampleRate();
  job_.start = input_.origin();
  job_.end = Stamp{job_.start.ns + std::llround(input_.frameTime(frames - 1) * 1e9)};
  job_.torque = held_torque;
  job_.channels.clear();
  job_.channel_shaft.clear();
  for (std::size_t c = 0; c < columns; ++c) {
    job_.channels.push_back(input_.column(c).name);
    job_.channel_shaft.push_back(input_.column(c).shaft);
  }
  const auto& teeth = estimator_.mesh().geometry().spec().teeth;
  job_.pinion_teeth = teeth[0];
  job_.gear_teeth = teeth[1];
  job_.max_order = max_order_;
  job_.block_rows = block_rows_;
  predict(held_torque);
  apply_at_ = Stamp{job_.end.ns + std::llround(kApplyDelay * 1e9)};
  auto identify = [job = &job_]() {
    Outcome out;
    try {
      out.report = identifyModes(*job);
    } catch (const Error& e) {
      out.error = e.what();
    }
    return out;
  };
  // Deferred: run by apply() in the caller's thread, at the same input as the worker's result.
  pending_ = std::async(worker_ ? std::launch::async : std::launch::deferred, identify);
}

void ModalStage::apply(Stamp stamp, PipelineSink& sink) {
  const Outcome outcome = pending_.get();
  pending_ = {};
  if (!outcome.error.empty()) {
    ++counters_.modal_errors;
    counters_.last_event = "modal identification: " + outcome.error;
    return;
  }
  const ModalReport& r = outcome.report;
  try {
    sink.modalIdentification(r.end, r);
    ++counters_.modal_out;
  } catch (const Error& e) {
    ++counters_.modal_errors;
    counters_.last_event = std::string("modal identification: ") + e.what();
  }
  // The matched, resolved frequencies with a standard deviation into the calibration.
  std::array<ModalFrequency, 3> frequencies;
  std::size_t count = 0;
  for (std::size_t i = 0; i < r.modes.size() && count < 3; ++i) {
    const modal::IdentifiedMode& m = r.modes[i];
    const int k = r.model_mode[i];
    if (k < 0 || m.unresolved || r.identified[k] != static_cast<int>(i)) continue;
    if (!(std::isfinite(m.frequency_std) && m.frequency_std > 0.0)) continue;
    frequencies[count++] = {k, m.frequency, m.frequency_std};
  }
  if (count > 0) calibration_.modal(stamp, frequencies.data(), count, r.torque, sink);
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
constexpr double kTwoPi = 6.283185307179586;
}

const char* toString(InputOutcome outcome) {
  switch (outcome) {
    case InputOutcome::kAccepted: return "accepted";
    case InputOutcome::kZeroStamp: return "zero stamp";
    case InputOutcome::kOutOfOrder: return "out of order";
    case InputOutcome::kInvalidValue: return "invalid value";
    case InputOutcome::kUnreachableLoad: return "unreachable load";
  }
  return "?";
}

std::vector<std::pair<std::string, std::uint64_t>> namedCounters(const PipelineCounters& c) {
  return {{"accepted_torque", c.accepted_torque},         {"rejected_torque", c.rejected_torque},
          {"accepted_preload", c.accepted_preload},       {"rejected_preload", c.rejected_preload},
          {"rejected_zero_stamp", c.zero_stamps},         {"rejected_out_of_order", c.out_of_order},
          {"rejected_invalid_value", c.invalid_values},   {"unreachable_loads", c.unreachable_loads},
          {"clock_jump_resets", c.clock_resets},          {"stamp_jump_resets", c.stamp_resets},
          {"gap_restarts", c.gap_restarts},               {"dynamics_errors", c.dynamics_errors},
          {"stiffness_published", c.stiffness_out},       {"stiffness_coalesced", c.stiffness_coalesced},
          {"transmission_error_published", c.te_out},     {"te_spectra_published", c.spectra_out},
          {"resonance_published", c.resonance_out},       {"modal_updates", c.modal_updates}};
}

void PipelineOptions::validate() const {
  requirePositive("max_abs_torque", limits.max_abs_torque);
  requirePositive("max_preload", limits.max_preload);
  requirePositive("max_interference", limits.max_interference);
  requireNonNegative("bearing_load_tolerance", limits.load_tolerance);
  if (limits.load_tolerance > 0.1) {
    throw InvalidInput("bearing_load_tolerance = " + formatValue(limits.load_tolerance) + ": must be <= 0.1");
  }
  requirePositive("output_rate", output_rate);
  if (output_rate > 1e6) throw InvalidInput("output_rate = " + formatValue(output_rate) + ": must be <= 1e6 Hz");
  requirePositive("max_gap", max_gap);
  if (max_gap * output_rate > DynamicsEstimator::kMaxSamplesPerAdvance) {
    throw InvalidInput("max_gap = " + formatValue(max_gap) + ": max_gap * output_rate must be <= 1e7 samples");
  }
  requireNonNegative("stamp_jump_back", stamp_jump_back);
  requireNonNegative("clock_jump_back", clock_jump_back);
  requirePositive("resonance_threshold", resonance_threshold);
  if (resonance_threshold >= 1.0) {
    throw InvalidInput("resonance_threshold = " + formatValue(resonance_threshold) + ": must be < 1 (relative)");
  }
  if (spectrum_window < 8 || spectrum_window > (1 << 20)) {
    throw InvalidInput("spectrum_window = " + std::to_string(spectrum_window) + ": must be in [8, 1048576] samples");
  }
  if (spectrum_hop < 1 || spectrum_hop > spectrum_window) {
    throw InvalidInput("spectrum_hop = " + std::to_string(spectrum_hop) + ": must be in [1, spectrum_window]");
  }
  requireFinite("pinion_speed_rpm", pinion_speed_rpm);
  if (std::abs(pinion_speed_rpm) > 1e5) {
    throw InvalidInput("pinion_speed_rpm = " + formatValue(pinion_speed_rpm) + ": must be within +-1e5 rpm");
  }
  requireNonNegative("stiffness_rate", stiffness_rate);
  if (stiffness_rate > 1e5) throw InvalidInput("stiffness_rate = " + formatValue(stiffness_rate) + ": must be <= 1e5 Hz");
}

RigPipeline::RigPipeline(const RigConfig& rig, const PipelineOptions& options) : rig_(rig), options_(options) {
  options_.validate();
  if (options_.dynamics && rig_.dynamics.present) {
    // One speed for both mesh phases: the stiffness estimate's and the dynamics' (their grid too).
    if (!(options_.pinion_speed_rpm > 0.0)) {
      throw InvalidInput("pinion_speed_rpm = " + formatValue(options_.pinion_speed_rpm) + ": must be > 0 with dynamics");
    }
    rig_.dynamics.speed_rpm = options_.pinion_speed_rpm;
  }
  estimator_ = std::make_unique<StiffnessEstimator>(rig_, options_.limits);
  pinion_speed_ = options_.pinion_speed_rpm * kTwoPi / 60.0;
  if (options_.dynamics) {
    dynamics_ = std::make_unique<DynamicsEstimator>(rig_, estimator_->shaftRadialStiffness(), options_.output_rate);
    dynamics_->setFidelity(options_.fidelity);
    te_spectrum_ = std::make_unique<SlidingSpectrum>(options_.spectrum_window, options_.spectrum_hop,
                                                     dynamics_->outputInterval(), 3);
  }
}

void RigPipeline::reset(const std::string& reason) {
  estimator_->reset();
  if (te_spectrum_) te_spectrum_->reset();
  if (dynamics_) {
    // The dynamics restart at the next torque input (their reset needs its time), with the bearing
    // stiffness of the configured preloads: rebuilt only if it moved by more than 1 %, as always.
    dynamics_->stop();
    try {
      dynamics_->setBearingStiffness(estimator_->shaftRadialStiffness());
    } catch (const std::exception& e) {
      dynamicsError("dynamics", e);
    }
  }
  last_torque_.reset();
  last_preload_.reset();
  last_stiffness_out_.reset();
  angle_origin_.reset();
  last_resonance_.reset();  // the next accepted input republishes the resonance
  counters_.last_event = "reset: " + reason;
}

bool RigPipeline::observeClock(Stamp now, PipelineSink& /*sink*/) {
  // A looping bag's first messages can arrive before its /clock jump (separate connections, and
  // /clock lags by up to its period): if the stamps already restarted (rule 2) since the last jump,
  // that jump is the same restart; it is not reset a second time.
  bool back = last_clock_ && secondsBetween(*last_clock_, now) > options_.clock_jump_back;
  if (back && stamps_restarted_) {
    stamps_restarted_ = false;
    back = false;
  }
  if (back) {
    ++counters_.clock_resets;
    reset("clock went back from " + formatValue(last_clock_->toSec()) + " s to " + formatValue(now.toSec()) + " s");
  }
  last_clock_ = now;
  return back;
}

InputOutcome RigPipeline::reject(InputOutcome why, const std::string& topic, const std::string& reason,
                                 std::uint64_t& rejected) {
  ++rejected;
  switch (why) {
    case InputOutcome::kZeroStamp: ++counters_.zero_stamps; break;
    case InputOutcome::kOutOfOrder: ++counters_.out_of_order; break;
    case InputOutcome::kInvalidValue: ++counters_.invalid_values; break;
    case InputOutcome::kUnreachableLoad: ++counters_.unreachable_loads; break;
    case InputOutcome::kAccepted: break;
  }
  counters_.last_event = topic + " rejected (" + toString(why) + "): " + reason;
  return why;
}

InputOutcome RigPipeline::checkStamp(Stamp stamp, std::optional<Stamp>& last, const std::string& topic,
                                     PipelineSink& /*sink*/) {
  if (stamp.isZero()) return InputOutcome::kZeroStamp;
  if (last && stamp < *last) {
    const double back = secondsBetween(*last, stamp);
    if (back <= options_.stamp_jump_back) return InputOutcome::kOutOfOrder;
    ++counters_.stamp_resets;
    stamps_restarted_ = true;
    reset(topic + " stamp went back by " + formatValue(back) + " s (more than ~stamp_jump_back): source restarted");
  }
  return InputOutcome::kAccepted;
}

double RigPipeline::pinionAngle(Stamp stamp) const {
  return angle_origin_ ? pinion_speed_ * secondsBetween(stamp, *angle_origin_) : 0.0;
}

template <typename Validate, typename Update>
InputOutcome RigPipeline::apply(const char* topic, Stamp stamp, std::optional<Stamp>& last, std::uint64_t& accepted,
                                std::uint64_t& rejected, PipelineSink& sink, Validate validate, Update update) {
  // Values first: a bad value must not trigger a stamp-rule reset before it is refused.
  try {
    validate();
  } catch (const InvalidInput& e) {
    return reject(InputOutcome::kInvalidValue, topic, e.what(), rejected);
  }
  const InputOutcome time_ok = checkStamp(stamp, last, topic, sink);
  if (time_ok != InputOutcome::kAccepted) {
    return reject(time_ok, topic, "stamp " + formatValue(stamp.toSec()) + " s", rejected);
  }
  try {
    const StiffnessEstimate& estimate = update();  // transactional: throws without changing the state
    ++accepted;
    last = stamp;
    afterUpdate(stamp, estimate, sink);
  } catch (const InvalidInput& e) {
    return reject(InputOutcome::kInvalidValue, topic, e.what(), rejected);
  } catch (const UnreachableLoad& e) {
    return reject(InputOutcome::kUnreachableLoad, topic, e.what(), rejected);
  }
  return InputOutcome::kAccepted;
}

InputOutcome RigPipeline::torque(Stamp stamp, double torque, PipelineSink& sink) {
  const InputOutcome outcome = apply(
      "torque", stamp, last_torque_, counters_.accepted_torque, counters_.rejected_torque, sink,
      [&] { estimator_->validateTorque(torque); },
      [&]() -> const StiffnessEstimate& {
        // The mesh phase counts from the first torque input after a (re)start, as the dynamics do;
        // the origin is kept only if the input is accepted.
        const Stamp origin = angle_origin_.value_or(stamp);
        const StiffnessEstimate& e = estimator_->setTorque(torque, pinion_speed_ * secondsBetween(stamp, origin));
        angle_origin_ = origin;
        return e;
      });
  if (outcome == InputOutcome::kAccepted && dynamics_) advanceDynamics(stamp, torque, sink);
  return outcome;
}

InputOutcome RigPipeline::preload(Stamp stamp, const std::vector<PreloadSetting>& settings, PipelineSink& sink) {
  return apply("preload", stamp, last_preload_, counters_.accepted_preload, counters_.rejected_preload, sink,
               [&] { estimator_->validatePreloads(settings); },
               [&]() -> const StiffnessEstimate& { return estimator_->setPreloads(settings); });
}

void RigPipeline::afterUpdate(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink) {
  // Coalescing by stamp, not by wall time, so a replay coalesces exactly as the live node did.
  const bool due = options_.stiffness_rate <= 0.0 || !last_stiffness_out_ || stamp < *last_stiffness_out_ ||
                   secondsBetween(stamp, *last_stiffness_out_) >= 1.0 / options_.stiffness_rate;
  if (due) {
    sink.stiffness(stamp, estimate);
    last_stiffness_out_ = stamp;
    ++counters_.stiffness_out;
  } else {
    ++counters_.stiffness_coalesced;
  }
  if (!dynamics_) return;
  // Every accepted input hands the new bearing stiffness to the dynamics (rebuilt only when it
  // moved by more than 1 %), then the resonance estimate is refreshed.
  try {
    dynamics_->setBearingStiffness(estimator_->shaftRadialStiffness());
  } catch (const std::exception& e) {
    dynamicsError("dynamics", e);
  }
  updateResonance(stamp, estimate, sink);
}

void RigPipeline::dynamicsError(const std::string& where, const std::exception& e) {
  ++counters_.dynamics_errors;
  counters_.last_event = where + ": " + e.what();
}

void RigPipeline::restartDynamics(Stamp stamp, double torque) {
  dynamics_epoch_ = stamp;
  dynamics_->reset(0.0, torque);
  te_spectrum_->reset();  // a new window: no samples from before the restart
  angle_origin_ = stamp;  // the stiffness message's mesh phase restarts with the dynamics
}

void RigPipeline::advanceDynamics(Stamp stamp, double torque, PipelineSink& sink) {
  try {
    const double t = dynamics_->started() ? secondsBetween(stamp, dynamics_epoch_) : 0.0;
    const bool gap = dynamics_->started() && t - dynamics_->time() > options_.max_gap;
    if (!dynamics_->started() || gap) {
      // Rule 4: a paused rig restarts the model at this input instead of integrating the gap.
      if (gap) {
        ++counters_.gap_restarts;
        counters_.last_event = "input gap of " + formatValue(t - dynamics_->time()) + " s (more than ~max_gap): dynamics restarted";
      }
      restartDynamics(stamp, torque);
      return;
    }
    const double from = dynamics_->time();
    dynamics_->advanceTo(t, [&](const DynamicsSample& relative) {
      DynamicsSample s = relative;
      const Stamp sample_stamp{dynamics_epoch_.ns + std::llround(relative.t * 1e9)};
      s.t = sample_stamp.toSec();
      sink.transmissionError(sample_stamp, s);
      ++counters_.te_out;
      if (te_spectrum_->push(s.dynamic_te)) {
        sink.spectrum(sample_stamp, *te_spectrum_);
        ++counters_.spectra_out;
      }
    });
    counters_.simulated_s += dynamics_->time() - from;
  } catch (const std::exception& e) {
    // The state stays at its last good sample and every later input would fail the same way:
    // restart the model here (counted), as after a gap.
    dynamicsError("dynamics (restarted at this input)", e);
    try {
      restartDynamics(stamp, torque);
    } catch (const std::exception& again) {
      dynamicsError("dynamics", again);
    }
  }
  try {
    dynamics_->setTorque(torque);  // the new torque holds from here on, whatever happened above
  } catch (const std::exception& e) {
    dynamicsError("dynamics", e);
  }
}

void RigPipeline::updateResonance(Stamp stamp, const StiffnessEstimate& estimate, PipelineSink& sink) {
  try {
    const std::array<double, 2> kb = estimator_->shaftRadialStiffness();
    const std::array<double, 3> springs{kb[0], kb[1], estimate.mesh.mean};
    // Skip the modal analysis when it cannot change the decision: K = sum k_i B_i with B_i >= 0,
    // so springs within a factor (1 +- eps) of those at the last publication bound every
    // eigenvalue omega^2 within the same factor (Courant-Fischer), and each frequency within
    // sqrt(1 +- eps), i.e. closer than eps = ~resonance_threshold: no republication would follow.
    if (last_resonance_) {
      bool within = true;
      for (int i = 0; i < 3 && within; ++i) {
        within = std::abs(springs[i] - springs_at_resonance_[i]) <= options_.resonance_threshold * springs_at_resonance_[i];
      }
      if (within) return;
    }
    const GearRotorParameters p = rigRotorParameters(rig_, estimator_->mesh(), kb);
    ResonanceEstimate r;
    r.modes = modalAnalysis(p, estimate.mesh.mean);
    ++counters_.modal_updates;
    bool moved = !last_resonance_;
    for (std::size_t i = 0; !moved && i < r.modes.size(); ++i) {
      const double last = last_resonance_->modes[i].natural_frequency;
      moved = std::abs(r.modes[i].natural_frequency - last) > options_.resonance_threshold * last;
    }
    if (!moved) return;
    for (const Mode& m : r.modes) {
      if (!std::isfinite(m.natural_frequency) || !std::isfinite(m.damping_ratio) || !std::isfinite(m.damped_frequency)) {
        throw InvalidInput("resonance: a modal result is not finite (not published)");  // never NaN on a topic
      }
    }
    double margin = 0.0;
    r.floquet_valid = dynamics_->floquetMargin(&margin) && std::isfinite(margin);
    r.floquet_margin = r.floquet_valid ? margin : 0.0;
    last_resonance_ = r;
    springs_at_resonance_ = springs;
    sink.resonance(stamp, r);
    ++counters_.resonance_out;
  } catch (const std::exception& e) {
    dynamicsError("resonance", e);
  }
}

void RigPipeline::setDamping(double mesh_damping_ratio, double bearing_damping_ratio) {
  // Each checked on its own, so that a refusal names the one that is out of range.
  requireNonNegative("mesh_damping_ratio", mesh_damping_ratio);
  requireAtMost("mesh_damping_ratio", mesh_damping_ratio, 1.0);
  requireNonNegative("bearing_damping_ratio", bearing_damping_ratio);
  requireAtMost("bearing_damping_ratio", bearing_damping_ratio, 1.0);
  rig_.dynamics.mesh_damping_ratio = mesh_damping_ratio;
  rig_.dynamics.bearing_damping_ratio = bearing_damping_ratio;
  if (dynamics_) dynamics_->setDamping(mesh_damping_ratio, bearing_damping_ratio);
  last_resonance_.reset();  // damped frequencies and ratios changed: republish at the next input
}

void RigPipeline::setFidelity(Fidelity fidelity) {
  options_.fidelity = fidelity;
  if (dynamics_) dynamics_->setFidelity(fidelity);
}

void RigPipeline::setStiffnessRate(double hz) {
  requireNonNegative("stiffness_rate", hz);
  options_.stiffness_rate = hz;
}

}  // namespace drivetrain_stiffness

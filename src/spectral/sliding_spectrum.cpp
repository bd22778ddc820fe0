#include "drivetrain_stiffness/spectral/sliding_spectrum.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
int validWindow(int window) {
  if (window < 8) throwInvalid("spectrum_window", window, "must be >= 8 samples");
  return window;
}
}  // namespace

SlidingSpectrum::SlidingSpectrum(int window, int hop, double dt, int peaks)
    : window_(window),
      hop_(hop),
      n_peaks_(peaks),
      dt_(dt),
      ring_(window > 0 ? window : 0, 0.0),
      ordered_(ring_.size()),
      analyzer_(validWindow(window), dt) {
  if (hop < 1 || hop > window) throwInvalid("spectrum_hop", hop, "must be in [1, spectrum_window]");
  if (peaks < 1) throwInvalid("spectrum_peaks", peaks, "must be >= 1");
  requirePositive("dt", dt);
  // A spectrum of window/2 + 1 bins has at most that many local maxima: reserved now, so that a
  // spectrum richer than any before it (a run-up sweeping the mesh orders) allocates nothing.
  scratch_.maxima.reserve(static_cast<std::size_t>(window / 2 + 1));
  scratch_.kept.reserve(static_cast<std::size_t>(window / 2 + 1));
  peaks_.reserve(static_cast<std::size_t>(peaks));
}

void SlidingSpectrum::reset() {
  count_ = 0;
  peaks_.clear();
}

bool SlidingSpectrum::push(double value) {
  requireFinite("spectrum sample", value);
  ring_[count_ % window_] = value;
  ++count_;
  if (count_ < window_ || (count_ - window_) % hop_ != 0) return false;
  // Unroll the ring into time order: the oldest sample sits at count_ % window_.
  for (int i = 0; i < window_; ++i) ordered_[i] = ring_[(count_ + i) % window_];
  topPeaks(analyzer_.compute(ordered_), n_peaks_, 3, scratch_, peaks_);
  return true;
}

}  // namespace drivetrain_stiffness

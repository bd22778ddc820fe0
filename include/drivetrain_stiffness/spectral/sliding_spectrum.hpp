// Spectral peaks of a sampled signal over a sliding window (the node's predicted transmission
// error): a ring buffer of `window` samples; every `hop` new samples the amplitude spectrum of the
// latest window is taken (spectrum.hpp) and its strongest peaks kept. ROS-free.
#pragma once

#include <vector>

#include "drivetrain_stiffness/spectral/spectrum.hpp"

namespace drivetrain_stiffness {

class SlidingSpectrum {
 public:
  /// window >= 8 samples, 1 <= hop <= window, dt > 0, peaks >= 1 (InvalidInput otherwise).
  SlidingSpectrum(int window, int hop, double dt, int peaks = 3);
  /// Adds one sample (non-finite values are refused with InvalidInput); returns true when a new
  /// set of peaks was computed.
  bool push(double value);
  const std::vector<SpectralPeak>& peaks() const { return peaks_; }
  double resolution() const { return 1.0 / (window_ * dt_); }  ///< [Hz]
  double windowSeconds() const { return window_ * dt_; }
  void reset();

 private:
  int window_, hop_, n_peaks_;
  double dt_;
  std::vector<double> ring_, ordered_;
  SpectrumAnalyzer analyzer_;  ///< plan made once: no planning inside the node's callbacks
  long count_ = 0;
  std::vector<SpectralPeak> peaks_;
  PeakScratch scratch_;  ///< topPeaks' storage, kept between hops
};

}  // namespace drivetrain_stiffness

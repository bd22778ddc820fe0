// The strongest spectral lines over a sliding window of samples (the node's predicted TE).
#pragma once

#include <vector>

#include "drivetrain_stiffness/spectral/spectrum.hpp"

namespace drivetrain_stiffness {

class SlidingSpectrum {
 public:
  /// window >= 8 and 1 <= hop <= window [samples], dt > 0 [s], peaks >= 1; InvalidInput otherwise.
  SlidingSpectrum(int window, int hop, double dt, int peaks = 3);
  /// Adds one sample; true when a new set of peaks (every `hop` samples) was computed. Throws
  /// InvalidInput for a non-finite value.
  bool push(double value);
  const std::vector<SpectralPeak>& peaks() const { return peaks_; }
  double resolution() const { return 1.0 / (window_ * dt_); }  ///< [Hz]
  double windowSeconds() const { return window_ * dt_; }
  void reset();

 private:
  int window_, hop_, n_peaks_;
  double dt_;
  std::vector<double> ring_, ordered_;
  SpectrumAnalyzer analyzer_;
  long count_ = 0;
  std::vector<SpectralPeak> peaks_;
  PeakScratch scratch_;
};

}  // namespace drivetrain_stiffness

// Amplitude spectra and peak picking (FFTW), for the resonance estimates of issue 5.
//
// amplitudeSpectrum: one-sided spectrum of a real signal (mean removed, Hann window), scaled so a
// sine of amplitude A shows a peak of height A (2 |X_k| / sum of the window).
// topPeaks: the largest local maxima above DC, each refined below the bin spacing by fitting a
// parabola to the log amplitudes of the three bins around it (Gaussian interpolation; its bias for
// the Hann window is bounded in test_spectrum.cpp).
#pragma once

#include <vector>

namespace drivetrain_stiffness {

struct Spectrum {
  std::vector<double> frequency;  ///< [Hz]
  std::vector<double> amplitude;  ///< same unit as the signal
  double resolution = 0.0;        ///< bin spacing [Hz]
};

struct SpectralPeak {
  double frequency = 0.0;  ///< [Hz], interpolated
  double amplitude = 0.0;  ///< interpolated
};

/// x sampled every dt [s]; at least 8 samples, all finite (InvalidInput otherwise).
Spectrum amplitudeSpectrum(const std::vector<double>& x, double dt);

/// amplitudeSpectrum for a fixed length, with the FFTW plan and buffers made once: what a sliding
/// spectrum inside a real-time callback needs (planning takes ~1.5 ms for 1024 points, executing a
/// few microseconds). FFTW's planner is not thread-safe; plans are made and destroyed under one
/// process-wide lock, so several instances (nodelets) may be built concurrently.
class SpectrumAnalyzer {
 public:
  SpectrumAnalyzer(int n, double dt);  ///< n >= 8 samples, dt > 0 (InvalidInput otherwise)
  ~SpectrumAnalyzer();
  SpectrumAnalyzer(const SpectrumAnalyzer&) = delete;
  SpectrumAnalyzer& operator=(const SpectrumAnalyzer&) = delete;
  /// x.size() == n, all finite; the result stays valid until the next call.
  const Spectrum& compute(const std::vector<double>& x);

 private:
  int n_;
  std::vector<double> window_, in_;
  double window_sum_ = 0.0;
  struct Plan;
  Plan* plan_ = nullptr;
  Spectrum out_;
};

/// The n largest peaks (local maxima at least `min_separation` bins apart), strongest first.
std::vector<SpectralPeak> topPeaks(const Spectrum& s, int n, int min_separation = 3);

/// Storage topPeaks works in; kept by a caller that repeats it (no allocation once it has grown).
struct PeakScratch {
  std::vector<std::size_t> maxima, kept;
};
/// The same peaks into `out`, working in `scratch` (the sliding spectrum's per-hop path).
void topPeaks(const Spectrum& s, int n, int min_separation, PeakScratch& scratch,
              std::vector<SpectralPeak>& out);

/// Peaks of a sampled curve y(x) on a uniform grid (a frequency sweep's RMS), same refinement.
std::vector<SpectralPeak> curvePeaks(const std::vector<double>& x, const std::vector<double>& y,
                                     int n);

}  // namespace drivetrain_stiffness

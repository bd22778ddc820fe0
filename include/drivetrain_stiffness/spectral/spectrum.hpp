// Amplitude spectra and peak picking (FFTW): docs/resonance.md "Spectra and peaks".
#pragma once

#include <vector>

namespace drivetrain_stiffness {

struct Spectrum {
  std::vector<double> frequency;  ///< [Hz]
  std::vector<double> amplitude;  ///< the signal's unit
  double resolution = 0.0;        ///< [Hz]
};

struct SpectralPeak {
  double frequency = 0.0;  ///< [Hz], interpolated
  double amplitude = 0.0;  ///< interpolated
};

/// The one-sided Hann spectrum of x sampled every dt [s], mean removed, a sine of amplitude A
/// giving a peak of A (2 |X_k| / sum of the window). Throws InvalidInput unless x has >= 8 finite
/// samples.
Spectrum amplitudeSpectrum(const std::vector<double>& x, double dt);

/// amplitudeSpectrum for a fixed length, the FFTW plan made once (under a process-wide lock: the
/// planner is not thread-safe).
class SpectrumAnalyzer {
 public:
  SpectrumAnalyzer(int n, double dt);  ///< n >= 8, dt > 0 [s]; InvalidInput otherwise
  ~SpectrumAnalyzer();
  SpectrumAnalyzer(const SpectrumAnalyzer&) = delete;
  SpectrumAnalyzer& operator=(const SpectrumAnalyzer&) = delete;
  /// x.size() == n, all finite; the result is valid until the next call.
  const Spectrum& compute(const std::vector<double>& x);

 private:
  int n_;
  std::vector<double> window_, in_;
  double window_sum_ = 0.0;
  struct Plan;
  Plan* plan_ = nullptr;
  Spectrum out_;
};

/// The n largest local maxima above DC at least `min_separation` bins apart, strongest first, each
/// refined by a parabola through the log amplitudes of its three bins.
std::vector<SpectralPeak> topPeaks(const Spectrum& s, int n, int min_separation = 3);

/// topPeaks' storage, for a caller that repeats it.
struct PeakScratch {
  std::vector<std::size_t> maxima, kept;
};
/// The same into `out`, allocation-free once `scratch` has grown.
void topPeaks(const Spectrum& s, int n, int min_separation, PeakScratch& scratch,
              std::vector<SpectralPeak>& out);

/// The peaks of y(x) on a uniform grid, refined the same way.
std::vector<SpectralPeak> curvePeaks(const std::vector<double>& x, const std::vector<double>& y,
                                     int n);

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/spectral/spectrum.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
constexpr double kPi = 3.14159265358979323846;

// Log-parabola through three positive values around index k: offset in bins and peak height.
void refine(double a, double b, double c, double* offset, double* height) {
  *offset = 0.0;
  *height = b;
  if (a <= 0.0 || b <= 0.0 || c <= 0.0) return;
  const double la = std::log(a), lb = std::log(b), lc = std::log(c);
  const double denom = la - 2.0 * lb + lc;
  if (!(denom < 0.0)) return;
  *offset = 0.5 * (la - lc) / denom;
  *height = std::exp(lb - 0.25 * (la - lc) * *offset);
}

std::vector<SpectralPeak> peaksOf(const std::vector<double>& x, const std::vector<double>& y, int n, int separation,
                                  std::size_t first) {
  std::vector<std::size_t> maxima;
  for (std::size_t k = std::max<std::size_t>(first, 1); k + 1 < y.size(); ++k) {
    if (y[k] > y[k - 1] && y[k] >= y[k + 1]) maxima.push_back(k);
  }
  std::sort(maxima.begin(), maxima.end(), [&](std::size_t a, std::size_t b) { return y[a] > y[b]; });
  std::vector<std::size_t> kept;
  for (std::size_t k : maxima) {
    bool near = false;
    for (std::size_t j : kept) near |= (k > j ? k - j : j - k) < static_cast<std::size_t>(separation);
    if (!near) kept.push_back(k);
    if (static_cast<int>(kept.size()) == n) break;
  }
  const double step = x.size() > 1 ? x[1] - x[0] : 0.0;
  std::vector<SpectralPeak> out;
  for (std::size_t k : kept) {
    double offset, height;
    refine(y[k - 1], y[k], y[k + 1], &offset, &height);
    out.push_back({x[k] + offset * step, height});
  }
  return out;
}
}  // namespace

Spectrum amplitudeSpectrum(const std::vector<double>& x, double dt) {
  requirePositive("dt", dt);
  if (x.size() < 8) throwInvalid("samples", static_cast<double>(x.size()), "need at least 8 samples for a spectrum");
  double mean = 0.0;
  for (double v : x) {
    requireFinite("signal", v);
    mean += v / x.size();
  }
  const int n = static_cast<int>(x.size());
  std::vector<double> in(n);
  double window_sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * kPi * i / n);  // periodic Hann
    in[i] = (x[i] - mean) * w;
    window_sum += w;
  }
  std::vector<std::complex<double>> out(n / 2 + 1);
  fftw_plan plan = fftw_plan_dft_r2c_1d(n, in.data(), reinterpret_cast<fftw_complex*>(out.data()), FFTW_ESTIMATE);
  fftw_execute(plan);
  fftw_destroy_plan(plan);
  Spectrum s;
  s.resolution = 1.0 / (n * dt);
  for (int k = 0; k <= n / 2; ++k) {
    s.frequency.push_back(k * s.resolution);
    s.amplitude.push_back(2.0 * std::abs(out[k]) / window_sum);
  }
  return s;
}

std::vector<SpectralPeak> topPeaks(const Spectrum& s, int n, int min_separation) {
  if (n < 1) throwInvalid("peaks", n, "must be >= 1");
  return peaksOf(s.frequency, s.amplitude, n, min_separation, 2);  // skip DC and its window leakage
}

std::vector<SpectralPeak> curvePeaks(const std::vector<double>& x, const std::vector<double>& y, int n) {
  if (x.size() != y.size() || x.size() < 3) throw InvalidInput("curvePeaks: need matching x and y with at least 3 points");
  return peaksOf(x, y, n, 2, 1);
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/spectral/spectrum.hpp"

#include <fftw3.h>

#include <mutex>

#include <algorithm>
#include <cmath>
#include <complex>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

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

void peaksOf(const std::vector<double>& x, const std::vector<double>& y, int n, int separation,
             std::size_t first, PeakScratch& scratch, std::vector<SpectralPeak>& out) {
  std::vector<std::size_t>& maxima = scratch.maxima;
  maxima.clear();
  for (std::size_t k = std::max<std::size_t>(first, 1); k + 1 < y.size(); ++k) {
    if (y[k] > y[k - 1] && y[k] >= y[k + 1]) maxima.push_back(k);
  }
  std::sort(maxima.begin(), maxima.end(),
            [&](std::size_t a, std::size_t b) { return y[a] > y[b]; });
  std::vector<std::size_t>& kept = scratch.kept;
  kept.clear();
  for (std::size_t k : maxima) {
    bool near = false;
    for (std::size_t j : kept)
      near |= (k > j ? k - j : j - k) < static_cast<std::size_t>(separation);
    if (!near) kept.push_back(k);
    if (static_cast<int>(kept.size()) == n) break;
  }
  const double step = x.size() > 1 ? x[1] - x[0] : 0.0;
  out.clear();
  for (std::size_t k : kept) {
    double offset, height;
    refine(y[k - 1], y[k], y[k + 1], &offset, &height);
    out.push_back({x[k] + offset * step, height});
  }
}

std::vector<SpectralPeak> peaksOf(const std::vector<double>& x, const std::vector<double>& y, int n,
                                  int separation, std::size_t first) {
  PeakScratch scratch;
  std::vector<SpectralPeak> out;
  peaksOf(x, y, n, separation, first, scratch, out);
  return out;
}
}  // namespace

namespace {
std::mutex& plannerMutex() {  // FFTW's planner (plan creation and destruction) is not thread-safe
  static std::mutex m;
  return m;
}
}  // namespace

struct SpectrumAnalyzer::Plan {
  std::vector<std::complex<double>> out;
  fftw_plan plan = nullptr;
};

SpectrumAnalyzer::SpectrumAnalyzer(int n, double dt) : n_(n) {
  requirePositive("dt", dt);
  if (n < 8) throwInvalid("samples", n, "need at least 8 samples for a spectrum");
  window_.resize(n);
  in_.resize(n);
  for (int i = 0; i < n; ++i) {
    window_[i] = 0.5 - 0.5 * std::cos(2.0 * kPi * i / n);  // periodic Hann
    window_sum_ += window_[i];
  }
  plan_ = new Plan;
  plan_->out.resize(n / 2 + 1);
  {
    std::lock_guard<std::mutex> lock(plannerMutex());
    plan_->plan = fftw_plan_dft_r2c_1d(
        n, in_.data(), reinterpret_cast<fftw_complex*>(plan_->out.data()), FFTW_ESTIMATE);
  }
  out_.resolution = 1.0 / (n * dt);
  for (int k = 0; k <= n / 2; ++k) out_.frequency.push_back(k * out_.resolution);
  out_.amplitude.assign(n / 2 + 1, 0.0);
}

SpectrumAnalyzer::~SpectrumAnalyzer() {
  std::lock_guard<std::mutex> lock(plannerMutex());
  fftw_destroy_plan(plan_->plan);
  delete plan_;
}

const Spectrum& SpectrumAnalyzer::compute(const std::vector<double>& x) {
  if (static_cast<int>(x.size()) != n_)
    throwInvalid("samples", static_cast<double>(x.size()), "must equal the analyzer length");
  double mean = 0.0;
  for (double v : x) {
    requireFinite("signal", v);
    mean += v / n_;
  }
  for (int i = 0; i < n_; ++i) in_[i] = (x[i] - mean) * window_[i];
  fftw_execute(plan_->plan);  // executing a plan is thread-safe
  for (int k = 0; k <= n_ / 2; ++k) out_.amplitude[k] = 2.0 * std::abs(plan_->out[k]) / window_sum_;
  return out_;
}

Spectrum amplitudeSpectrum(const std::vector<double>& x, double dt) {
  if (x.size() < 8)
    throwInvalid("samples", static_cast<double>(x.size()),
                 "need at least 8 samples for a spectrum");
  SpectrumAnalyzer analyzer(static_cast<int>(x.size()), dt);
  return analyzer.compute(x);
}

std::vector<SpectralPeak> topPeaks(const Spectrum& s, int n, int min_separation) {
  PeakScratch scratch;
  std::vector<SpectralPeak> out;
  topPeaks(s, n, min_separation, scratch, out);
  return out;
}

void topPeaks(const Spectrum& s, int n, int min_separation, PeakScratch& scratch,
              std::vector<SpectralPeak>& out) {
  if (n < 1) throwInvalid("peaks", n, "must be >= 1");
  peaksOf(s.frequency, s.amplitude, n, min_separation, 2, scratch,
          out);  // skip DC and its window leakage
}

std::vector<SpectralPeak> curvePeaks(const std::vector<double>& x, const std::vector<double>& y,
                                     int n) {
  if (x.size() != y.size() || x.size() < 3)
    throw InvalidInput("curvePeaks: need matching x and y with at least 3 points");
  return peaksOf(x, y, n, 2, 1);
}

}  // namespace drivetrain_stiffness

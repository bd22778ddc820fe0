// Output-only test records with known poles: n classically damped modes, each an exactly
// discretised single-degree-of-freedom oscillator (the closed-form transition matrix of
// q'' + 2 zeta w q' + w^2 q = 0 over one sample, so its discrete poles are exp(lambda_c / fs)
// exactly), driven by Gaussian white noise at every sample; the channels see y = Phi q plus white
// measurement noise.
#pragma once

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include <Eigen/Core>

namespace drivetrain_stiffness::modal::test {

struct TrueMode {
  double frequency;  ///< undamped [Hz]
  double damping;    ///< [-]
};

class SyntheticModes {
 public:
  /// `shapes`: channels x modes, real.
  SyntheticModes(std::vector<TrueMode> modes, Eigen::MatrixXd shapes, double sample_rate)
      : modes_(std::move(modes)), shapes_(std::move(shapes)), fs_(sample_rate) {
    const double dt = 1.0 / fs_;
    for (const TrueMode& m : modes_) {
      const double w = 2.0 * M_PI * m.frequency, z = m.damping, wd = w * std::sqrt(1.0 - z * z);
      const double e = std::exp(-z * w * dt), c = std::cos(wd * dt), s = std::sin(wd * dt);
      Eigen::Matrix2d phi;  // [q, q'] over one sample, closed form
      phi << e * (c + z * w / wd * s), e * s / wd, -e * w * w / wd * s, e * (c - z * w / wd * s);
      transitions_.push_back(phi);
    }
  }

  /// The continuous-time pole with Im > 0 of mode k [1/s].
  std::complex<double> pole(int k) const {
    const double w = 2.0 * M_PI * modes_[k].frequency, z = modes_[k].damping;
    return {-z * w, w * std::sqrt(1.0 - z * z)};
  }

  /// A record of `samples` samples after `warmup` samples of settling; measurement noise of
  /// `noise` times each channel's response rms (taken from the modal variance). `common`: every
  /// mode driven by one white input, as a rig's modes by the mesh force (the channels' lag
  /// covariances are then not symmetric), instead of one input per mode.
  Eigen::MatrixXd record(long samples, unsigned seed, double noise = 0.05, long warmup = 2000,
                         bool common = false) const {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    const int nm = static_cast<int>(modes_.size());
    std::vector<Eigen::Vector2d> x(nm, Eigen::Vector2d::Zero());
    Eigen::MatrixXd q(nm, samples);
    for (long t = -warmup; t < samples; ++t) {
      const double shared = common ? g(rng) : 0.0;
      for (int k = 0; k < nm; ++k) {
        // A velocity kick per sample, scaled so that each mode's displacement is O(1).
        const double w = 2.0 * M_PI * modes_[k].frequency;
        x[k] = transitions_[k] * x[k];
        x[k][1] += w * std::sqrt(modes_[k].damping) * (common ? shared : g(rng));
        if (t >= 0) q(k, t) = x[k][0];
      }
    }
    Eigen::MatrixXd y = shapes_ * q;
    for (long c = 0; c < y.rows(); ++c) {
      const double rms = std::sqrt(y.row(c).squaredNorm() / samples);
      for (long t = 0; t < samples; ++t) y(c, t) += noise * rms * g(rng);
    }
    return y;
  }

  const Eigen::MatrixXd& shapes() const { return shapes_; }
  double sampleRate() const { return fs_; }

 private:
  std::vector<TrueMode> modes_;
  Eigen::MatrixXd shapes_;
  double fs_;
  std::vector<Eigen::Matrix2d> transitions_;
};

/// The rig's two transverse modes (gear 7.9 kHz, pinion 9.4 kHz) seen by two housings at
/// 51.2 kHz.
inline SyntheticModes rigModes(double fs = 51200.0) {
  Eigen::MatrixXd shapes(2, 2);
  shapes << 1.0, 0.3, 0.4, -1.0;
  return SyntheticModes({{7900.0, 0.02}, {9400.0, 0.015}}, shapes, fs);
}

}  // namespace drivetrain_stiffness::modal::test

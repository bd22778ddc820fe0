// Covariance-driven stochastic subspace identification (SSI-COV) of an output-only record, with the
// first-order standard deviation of every pole's frequency and damping ratio from the record's own
// block-to-block scatter. Method, assumptions and sources: docs/vibration.md, "SSI-COV" and
// "Variance propagation". Allocates per call (it runs off the input path), never per sample inside.
#pragma once

#include <complex>
#include <vector>

#include <Eigen/Core>

namespace drivetrain_stiffness::modal {

/// Settings of one identification.
struct SsiOptions {
  int block_rows = 0;        ///< i: lags 1..2i-1 in an i x i block Hankel; 0: the smallest valid
  int min_order = 2;         ///< first model order (even, >= 2)
  int max_order = 40;        ///< last model order (even); (i - 1) * channels >= max_order
  int variance_blocks = 50;  ///< n_b records' blocks for the Hankel covariance; 0: no std
  /// p: the Hankel starts at lag p + 1 (lags p + 1..p + 2i - 1), past the span over which the
  /// acquisition chain's filter correlates the output's noise and direct term (>= 0)
  int skipped_lags = 0;
};

/// One continuous-time pole of one model order (the one of a conjugate pair with Im > 0).
struct Pole {
  int order = 0;                    ///< model order n
  std::complex<double> eigenvalue;  ///< lambda_c [1/s]
  double frequency = 0.0;           ///< undamped natural frequency |lambda_c| / 2 pi [Hz]
  double damping = 0.0;             ///< -Re lambda_c / |lambda_c| [-]
  double frequency_std = 0.0;       ///< [Hz]; NaN without variance blocks
  double damping_std = 0.0;         ///< [-]; NaN without variance blocks
  Eigen::VectorXcd shape;           ///< over the channels, largest entry 1
};

/// Poles of every model order min_order, min_order + 2, ..., max_order.
struct SsiResult {
  std::vector<Pole> poles;
  double sample_rate = 0.0;  ///< [Hz]
  int channels = 0;
  int block_rows = 0;
  int skipped_lags = 0;
  int min_order = 0, max_order = 0;
  int variance_blocks = 0;  ///< 0 when no std was computed
};

class SsiCov {
 public:
  /// Validates the orders and blocks; throws InvalidInput naming the field and value.
  explicit SsiCov(const SsiOptions& options = {});

  /// Identifies the poles of a channels x samples record sampled at `sample_rate` [Hz]; the mean
  /// of each channel is removed first. Throws InvalidInput for fewer than 1 channel, a
  /// non-finite sample, a non-positive rate, too few samples for the lags and blocks, or block
  /// rows too few for max_order with this channel count.
  SsiResult identify(const Eigen::Ref<const Eigen::MatrixXd>& record, double sample_rate) const;

  const SsiOptions& options() const { return options_; }
  /// The block rows used for `channels` channels (options().block_rows or the smallest valid).
  int blockRows(int channels) const;

 private:
  SsiOptions options_;
};

}  // namespace drivetrain_stiffness::modal

// Removal of the shaft and mesh orders from a record before identification: per sub-block and
// channel, a least-squares fit of cos and sin of each order times the measured angle, subtracted
// (the angle-domain order regression of the calibration, OrderRegression, applied to each
// accelerometer channel). The orders' instantaneous frequency bands, folded into [0, fs/2], are
// what selectModes sets aside: a mesh order is never reported as a mode. docs/vibration.md,
// "Mesh-order removal".
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/modal/pole_selection.hpp"

namespace drivetrain_stiffness::modal {

struct OrderRemovalOptions {
  /// Orders of the angle to remove [-] (> 0): with the pinion angle, e.g. 1, 2 (shaft) and
  /// z_p, 2 z_p, 3 z_p (mesh harmonics); with the mesh phase times 2 pi, 1, 2, 3.
  std::vector<double> orders;
  long block_samples = 1024;  ///< sub-block of the regression [samples] (>= 16)
  double band_margin = 0.01;  ///< relative widening of each order's band [-]
};

class OrderRemoval {
 public:
  /// Throws InvalidInput naming an order <= 0 or non-finite, block_samples < 16 or a negative
  /// or non-finite margin.
  explicit OrderRemoval(OrderRemovalOptions options);

  /// Subtracts the fitted orders from the channels x samples `record` in place; `angle` [rad]
  /// is the measured, unwrapped angle at each sample. Allocates per call (the design matrix),
  /// not per sample. Throws InvalidInput when the sizes differ, a value is not finite or the
  /// record is shorter than one block.
  void remove(Eigen::Ref<Eigen::MatrixXd> record, const Eigen::Ref<const Eigen::VectorXd>& angle,
              double sample_rate) const;

  /// Each order's instantaneous frequency range over the record (from the angle's rate at each
  /// block's ends), widened by band_margin and the regression's resolution sample_rate /
  /// block_samples, folded into [0, sample_rate / 2] and merged [Hz]. Same throws as remove.
  std::vector<FrequencyBand> bands(const Eigen::Ref<const Eigen::VectorXd>& angle,
                                   double sample_rate) const;

  const OrderRemovalOptions& options() const { return options_; }

 private:
  void check(long samples, const Eigen::Ref<const Eigen::VectorXd>& angle,
             double sample_rate) const;
  OrderRemovalOptions options_;
};

/// Time-synchronous averaging (Braun 1975; McFadden 1987): subtracts from each channel of the
/// channels x samples `record` its mean waveform over the cycles of an order, every harmonic of
/// that order at once at a cost linear in the samples. `cycles`: the order's unwrapped cycle count
/// at each sample (z_p x pinion angle / 2 pi for the mesh). Per sub-block of `block_samples`: four
/// bins per sample of one cycle (8 to 8192), the mean interpolated linearly between bin centres; a
/// sub-block of fewer than 8 whole cycles is left as it is. Throws InvalidInput when the sizes
/// differ, a value is not finite or block_samples < 16.
void removeSynchronousAverage(Eigen::Ref<Eigen::MatrixXd> record,
                              const Eigen::Ref<const Eigen::VectorXd>& cycles, long block_samples);

}  // namespace drivetrain_stiffness::modal

#include "drivetrain_stiffness/modal/order_removal.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/QR>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness::modal {
namespace {

/// Block b's first sample and length: blocks of `block` samples, the remainder joined to the last.
void blockSpan(long samples, long block, long b, long& first, long& length) {
  const long count = std::max(1L, samples / block);
  first = b * block;
  length = (b == count - 1) ? samples - first : block;
}

/// The angle's rate at sample t [rad/s] from a centred difference over up to 8 samples a side.
double rate(const Eigen::Ref<const Eigen::VectorXd>& angle, long t, long first, long last,
            double sample_rate) {
  const long a = std::max(first, t - 8), b = std::min(last, t + 8);
  return (angle[b] - angle[a]) * sample_rate / static_cast<double>(b - a);
}

/// [lo, hi] [Hz] aliased into [0, fs / 2]: one interval per Nyquist zone it crosses.
void fold(double lo, double hi, double fs, const std::string& label,
          std::vector<FrequencyBand>& out) {
  const double h = 0.5 * fs;
  lo = std::max(0.0, lo);
  if (hi < lo) return;
  const long k0 = static_cast<long>(std::floor(lo / h)), k1 = static_cast<long>(std::floor(hi / h));
  for (long k = k0; k <= k1; ++k) {
    const double a = std::max(lo, k * h), b = std::min(hi, (k + 1) * h);
    FrequencyBand band;
    band.label = label;
    if (k % 2 == 0) {
      band.low = a - k * h;
      band.high = b - k * h;
    } else {
      band.low = (k + 1) * h - b;
      band.high = (k + 1) * h - a;
    }
    out.push_back(band);
    if (k - k0 > 64) break;  // a range over 32 sampling rates covers [0, fs / 2] already
  }
}

}  // namespace

OrderRemoval::OrderRemoval(OrderRemovalOptions options) : options_(std::move(options)) {
  for (size_t k = 0; k < options_.orders.size(); ++k)
    requirePositive("order_removal.orders[" + std::to_string(k) + "]", options_.orders[k]);
  if (options_.block_samples < 16)
    throwInvalid("order_removal.block_samples", static_cast<double>(options_.block_samples),
                 "must be >= 16");
  requireNonNegative("order_removal.band_margin", options_.band_margin);
}

void OrderRemoval::check(long samples, const Eigen::Ref<const Eigen::VectorXd>& angle,
                         double sample_rate) const {
  requirePositive("sample_rate", sample_rate);
  if (angle.size() != samples)
    throwInvalid("angle.size", static_cast<double>(angle.size()),
                 "must equal the record's samples " + std::to_string(samples));
  if (samples < options_.block_samples)
    throwInvalid(
        "record.samples", static_cast<double>(samples),
        "must be >= order_removal.block_samples " + std::to_string(options_.block_samples));
  if (!angle.allFinite())  // the field is named only for the first bad sample
    for (long t = 0; t < samples; ++t)
      if (!std::isfinite(angle[t])) throwNotFinite("angle[" + std::to_string(t) + "]", angle[t]);
}

void OrderRemoval::remove(Eigen::Ref<Eigen::MatrixXd> record,
                          const Eigen::Ref<const Eigen::VectorXd>& angle,
                          double sample_rate) const {
  const long samples = record.cols();
  check(samples, angle, sample_rate);
  const int terms = 2 * static_cast<int>(options_.orders.size());
  if (terms == 0) return;
  const long block = options_.block_samples, count = std::max(1L, samples / block);
  // One design matrix and one QR for the call (the last block is shorter than 2 blocks).
  Eigen::MatrixXd design(2 * block, terms);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(2 * block, terms);
  for (long b = 0; b < count; ++b) {
    long first = 0, length = 0;
    blockSpan(samples, block, b, first, length);
    // x(t) ~ sum_o a_o cos(o theta(t)) + b_o sin(o theta(t)) over the block (least squares;
    // the regression of OrderRegression, docs/calibration.md "Measured TE").
    for (long t = 0; t < length; ++t)
      for (size_t o = 0; o < options_.orders.size(); ++o) {
        const double phase = options_.orders[o] * angle[first + t];
        design(t, 2 * o) = std::cos(phase);
        design(t, 2 * o + 1) = std::sin(phase);
      }
    // Rank-revealing: an order at 0 Hz or at fs / 2 in this block makes sin and cos collinear;
    // the QR leaves that column out.
    qr.compute(design.topRows(length));
    const Eigen::MatrixXd coefficients = qr.solve(record.middleCols(first, length).transpose());
    record.middleCols(first, length).noalias() -=
        (design.topRows(length) * coefficients).transpose();
  }
}

void removeSynchronousAverage(Eigen::Ref<Eigen::MatrixXd> record,
                              const Eigen::Ref<const Eigen::VectorXd>& cycles, long block_samples) {
  const long samples = record.cols();
  if (cycles.size() != samples)
    throwInvalid("cycles.size", static_cast<double>(cycles.size()),
                 "must equal the record's samples " + std::to_string(samples));
  if (block_samples < 16)
    throwInvalid("block_samples", static_cast<double>(block_samples), "must be >= 16");
  if (!cycles.allFinite())
    for (long t = 0; t < samples; ++t)
      if (!std::isfinite(cycles[t])) throwNotFinite("cycles[" + std::to_string(t) + "]", cycles[t]);
  const long channels = record.rows(), count = std::max(1L, samples / block_samples);
  Eigen::MatrixXd sum;
  Eigen::VectorXd hits;
  for (long b = 0; b < count; ++b) {
    long first = 0, length = 0;
    blockSpan(samples, block_samples, b, first, length);
    const double span = std::abs(cycles[first + length - 1] - cycles[first]);
    if (span < 8.0) continue;
    const long bins = std::clamp(std::lround(4.0 * static_cast<double>(length) / span), 8L, 8192L);
    sum.setZero(channels, bins);
    hits.setZero(bins);
    auto phase = [&](long t) {  // [0, bins): the position within the cycle, in bins
      const double c = cycles[t] - std::floor(cycles[t]);
      return std::min(c * static_cast<double>(bins), std::nextafter(bins, 0.0));
    };
    for (long t = first; t < first + length; ++t) {
      const long k = static_cast<long>(phase(t));
      sum.col(k) += record.col(t);
      hits[k] += 1.0;
    }
    for (long k = 0; k < bins; ++k)
      if (hits[k] > 0.0) sum.col(k) /= hits[k];
    // An empty bin (a speed change within the block) takes its neighbour's mean.
    for (long k = 0; k < bins; ++k)
      if (hits[k] == 0.0) sum.col(k) = sum.col((k + bins - 1) % bins);
    // The mean waveform at each sample: linear between bin centres, cyclic.
    for (long t = first; t < first + length; ++t) {
      const double x = phase(t) - 0.5;
      const double fl = std::floor(x), w = x - fl;
      const long k0 = (static_cast<long>(fl) + bins) % bins, k1 = (k0 + 1) % bins;
      record.col(t) -= (1.0 - w) * sum.col(k0) + w * sum.col(k1);
    }
  }
}

std::vector<FrequencyBand> OrderRemoval::bands(const Eigen::Ref<const Eigen::VectorXd>& angle,
                                               double sample_rate) const {
  const long samples = angle.size();
  check(samples, angle, sample_rate);
  const long block = options_.block_samples, count = std::max(1L, samples / block);
  const double resolution = sample_rate / static_cast<double>(block);
  std::vector<FrequencyBand> raw;
  for (double order : options_.orders) {
    const std::string label = "order " + formatValue(order);
    for (long b = 0; b < count; ++b) {
      long first = 0, length = 0;
      blockSpan(samples, block, b, first, length);
      const long last = first + length - 1;
      const double r0 = std::abs(rate(angle, first, 0, samples - 1, sample_rate));
      const double r1 = std::abs(rate(angle, last, 0, samples - 1, sample_rate));
      const double f0 = order * std::min(r0, r1) / kTwoPi, f1 = order * std::max(r0, r1) / kTwoPi;
      fold(f0 * (1.0 - options_.band_margin) - resolution,
           f1 * (1.0 + options_.band_margin) + resolution, sample_rate, label, raw);
    }
  }
  // Merge overlapping bands (keeping the first label).
  std::sort(raw.begin(), raw.end(),
            [](const FrequencyBand& x, const FrequencyBand& y) { return x.low < y.low; });
  std::vector<FrequencyBand> merged;
  for (const FrequencyBand& band : raw) {
    if (!merged.empty() && band.low <= merged.back().high) {
      merged.back().high = std::max(merged.back().high, band.high);
      if (merged.back().label.find(band.label) == std::string::npos)
        merged.back().label += ", " + band.label;
    } else {
      merged.push_back(band);
    }
  }
  return merged;
}

}  // namespace drivetrain_stiffness::modal

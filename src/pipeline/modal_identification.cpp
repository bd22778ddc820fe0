#include "drivetrain_stiffness/pipeline/modal_identification.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/modal/order_removal.hpp"
#include "drivetrain_stiffness/modal/ssi_cov.hpp"

namespace drivetrain_stiffness {

namespace {

/// Below this pinion speed the orders are not removed: their lines sit at a few hertz, far below
/// any transverse mode, and an angle that barely moves makes the regression singular [rad/s].
constexpr double kMinOrderSpeed = 1.0;
/// Mesh harmonics whose bands are reported at most (the synchronous average removes them all).
constexpr int kMaxMeshBands = 256;
/// A record whose quarter-second mean speeds all lie within this fraction of their mean is at
/// steady speed: its synchronous averages run over the whole record [-].
constexpr double kSteadySpeed = 0.01;

/// True when the pinion's mean speed over each quarter second of `angle` [rad] lies within
/// kSteadySpeed of the record's mean speed (docs/vibration.md "Identification in the pipeline").
bool steadySpeed(const Eigen::VectorXd& angle, double sample_rate) {
  const long n = angle.size(), piece = std::max(16L, std::lround(0.25 * sample_rate));
  if (n < 2) return false;
  const double mean = (angle[n - 1] - angle[0]) / static_cast<double>(n - 1);  // [rad/sample]
  if (!(std::abs(mean) > 0.0)) return false;
  for (long first = 0; first + piece <= n; first += piece) {
    const double speed = (angle[first + piece - 1] - angle[first]) / static_cast<double>(piece - 1);
    if (std::abs(speed - mean) > kSteadySpeed * std::abs(mean)) return false;
  }
  return true;
}

/// The bands of the removed orders over the record, lines_only (a mode shows through them): each
/// shaft's first two and every mesh harmonic below the flat band.
std::vector<modal::FrequencyBand> orderBands(const ModalJob& job, double max_speed) {
  const double ratio = static_cast<double>(job.pinion_teeth) / job.gear_teeth;
  modal::OrderRemovalOptions o;
  o.orders = {1.0, 2.0, ratio, 2.0 * ratio};
  const double bandwidth = job.band * job.sample_rate;
  const double mesh_frequency = job.pinion_teeth * max_speed / kTwoPi;  // [Hz]
  for (int k = 1; k <= kMaxMeshBands && k * mesh_frequency < bandwidth; ++k)
    o.orders.push_back(static_cast<double>(k) * job.pinion_teeth);
  o.block_samples = std::min<long>(job.angle.size(), std::lround(0.25 * job.sample_rate));
  o.block_samples = std::max<long>(16, o.block_samples);
  o.band_margin = 0.002;
  std::vector<modal::FrequencyBand> bands =
      modal::OrderRemoval(o).bands(job.angle, job.sample_rate);
  for (modal::FrequencyBand& b : bands) b.lines_only = true;
  return bands;
}

/// The model modes as seen by the channels: each column's coordinate, scaled so that the mode's
/// largest displacement over all coordinates is 1 (PredictedMode's convention).
std::vector<modal::PredictedMode> atChannels(const ModalJob& job) {
  std::vector<modal::PredictedMode> out;
  for (const ModelModePrediction& m : job.predicted) {
    modal::PredictedMode p;
    p.name = m.dominant;
    p.frequency = m.frequency;
    const double largest = m.shape.cwiseAbs().maxCoeff();
    p.shape = Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(job.channel_shaft.size()));
    for (std::size_t c = 0; c < job.channel_shaft.size(); ++c)
      p.shape[static_cast<Eigen::Index>(c)] =
          largest > 0.0 ? m.shape[job.channel_shaft[c]] / largest : 0.0;
    out.push_back(std::move(p));
  }
  return out;
}

std::string hertz(double f) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.0f Hz", f);
  return buffer;
}

}  // namespace

ModalReport identifyModes(const ModalJob& job) {
  ModalReport r;
  r.start = job.start;
  r.end = job.end;
  r.sample_rate = job.sample_rate;
  r.duration = static_cast<double>(job.record.cols()) / job.sample_rate;
  r.torque = job.torque;
  r.channels = job.channels;
  r.predicted = job.predicted;
  const long n = job.angle.size();
  r.pinion_speed = n > 1 ? (job.angle[n - 1] - job.angle[0]) * job.sample_rate / (n - 1) : 0.0;
  double max_speed = 0.0;
  for (long i = 1; i < n; i += 256)
    max_speed = std::max(max_speed, std::abs(job.angle[i] - job.angle[i - 1]) * job.sample_rate);

  // The orders out (docs/vibration.md "Identification in the pipeline"): synchronous averages
  // over the pinion's turns (every pinion-shaft order, 1 s blocks) and over the mesh cycles
  // (every mesh harmonic, 0.25 s blocks, as the speed changes faster than the pinion turns); at
  // steady speed both over the whole record, as an average over N cycles takes 1/N of the modes'
  // random response with it, which at lags near one cycle moves the modes ("Averaging blocks").
  Eigen::MatrixXd record = job.record;
  if (max_speed > kMinOrderSpeed) {
    const Eigen::VectorXd turns = job.angle / kTwoPi;
    const bool steady = steadySpeed(job.angle, job.sample_rate);
    auto block = [&](double seconds) {  // [samples]: the whole record at steady speed
      return std::max<long>(16, steady ? n : std::lround(seconds * job.sample_rate));
    };
    modal::removeSynchronousAverage(record, turns, block(1.0));
    modal::removeSynchronousAverage(record, turns * static_cast<double>(job.pinion_teeth),
                                    block(0.25));
    r.order_bands = orderBands(job, max_speed);
  }
  // Beyond the chain's flat band (~modal_band) the anti-alias filter rolls off: poles there are
  // its own.
  r.order_bands.push_back(
      {job.band * job.sample_rate, 0.5 * job.sample_rate, "beyond the flat band", false});
  modal::SsiOptions ssi_options;
  ssi_options.max_order = job.max_order;
  ssi_options.block_rows = job.block_rows;
  ssi_options.skipped_lags = job.skipped_lags;
  const modal::SsiResult ssi = modal::SsiCov(ssi_options).identify(record, job.sample_rate);
  const modal::SelectionResult selected = modal::selectModes(ssi, r.order_bands);
  r.modes = selected.modes;
  r.spurious_clusters = selected.spurious_clusters;
  for (std::size_t i = 0; i < ssi.poles.size(); ++i) {
    const modal::Pole& p = ssi.poles[i];
    r.poles.push_back({p.order, p.frequency, p.damping, p.frequency_std, p.damping_std,
                       selected.status[i], selected.mode_of[i]});
  }
  // A window of 35 %: a bearing scale 0.7 or 1.3 (the prior's 1-sigma range) moves its mode by
  // some 15 %, twice that at the prior's 2 sigma; the shape (MAC) tells the modes apart.
  modal::MatchOptions matching;
  matching.frequency_window = 0.35;
  const modal::MatchResult match =
      modal::matchModes(r.modes, atChannels(job), job.sample_rate, matching);
  r.model_mode = match.predicted_of;
  r.mac.resize(r.modes.size());
  for (std::size_t i = 0; i < r.modes.size(); ++i)
    r.mac[i] = r.model_mode[i] >= 0 ? match.mac_of[i] : 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    r.observability[k] = match.observability[k];
    r.identified[k] = match.identified_of[k];
  }
  return r;
}

std::string ModalReport::statement(std::size_t i) const {
  const modal::IdentifiedMode& m = modes.at(i);
  std::string s = "measured " + hertz(m.frequency);
  if (std::isfinite(m.frequency_std)) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, " +- %.3g Hz (1 sigma)", m.frequency_std);
    s += buffer;
  }
  const int k = model_mode.at(i);
  if (k < 0) return s + ", matching no model mode";
  s += " where the model predicts " + hertz(predicted[k].frequency) + " (" + predicted[k].dominant +
       ")";
  if (m.unresolved) s += "; a close mode these channels cannot separate";
  return s;
}

std::string ModalReport::modelStatement(std::size_t k) const {
  const ModelModePrediction& p = predicted.at(k);
  const std::string head = "the model's " + p.dominant + " mode at " + hertz(p.frequency);
  switch (observability[k]) {
    case modal::Observability::kAboveNyquist:
      return head + " is above the Nyquist frequency " + hertz(0.5 * sample_rate) +
             ": not observable";
    case modal::Observability::kNoChannel:
      return head + " moves none of the channels: not observable";
    case modal::Observability::kObservable: break;
  }
  if (identified[k] < 0) return head + " is observable but not identified in this record";
  return head + ": " + statement(static_cast<std::size_t>(identified[k]));
}

}  // namespace drivetrain_stiffness

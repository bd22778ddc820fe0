#include "drivetrain_stiffness/calibration/calibration_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {

const char* toString(WindowOutcome outcome) {
  switch (outcome) {
    case WindowOutcome::kNone: return "none";
    case WindowOutcome::kBaseline: return "baseline";
    case WindowOutcome::kUpdated: return "updated";
    case WindowOutcome::kGated: return "gated (normalised innovation above ~gate)";
    case WindowOutcome::kNoBaseline:
      return "no baseline yet (needs a window at |torque| <= ~baseline_torque)";
    case WindowOutcome::kTooSlow: return "not excited: slower than ~min_speed_rpm";
    case WindowOutcome::kNotQuasiStatic:
      return "not excited: mesh frequency above ~max_mesh_to_natural of the lowest mode";
    case WindowOutcome::kTooSparse:
      return "not excited: too few readings per mesh period for the second harmonic";
    case WindowOutcome::kIllConditioned:
      return "not excited: the readings do not determine the shaft orders";
  }
  return "?";
}

// ---- Progress: why no window has updated the estimate ----

double CalibrationProgress::windowSeconds(double speed) const {
  // The window rule closes a window once its readings span window_angle of pinion angle.
  return std::abs(speed) > 0.0 ? window_angle / std::abs(speed)
                               : std::numeric_limits<double>::infinity();
}

namespace {

/// The stretch that came nearer to closing a window: the larger angle (the window rule's measure),
/// then the longer time (a rig at rest spans no angle).
bool nearer(const SteadyStretch& a, const SteadyStretch& b) {
  if (a.readings == 0) return false;
  if (b.readings == 0) return true;
  return a.angle > b.angle || (a.angle == b.angle && a.duration > b.duration);
}

void keep(CalibrationProgress& p, const SteadyStretch& s, double baseline_torque) {
  if (s.readings == 0) return;
  p.smallest_torque = std::min(p.smallest_torque, std::abs(s.torque));
  // Unloaded or loaded by the rule a closed window is judged by (closeWindow: |T| <=
  // ~baseline_torque).
  SteadyStretch& kept = std::abs(s.torque) <= baseline_torque ? p.unloaded : p.loaded;
  if (nearer(s, kept)) kept = s;
}

/// printf into a string, for the sentences below (never on the per-reading path).
template <typename... Args>
std::string format(const char* spec, Args... args) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, spec, args...);
  return buffer;
}

std::string windowsCount(std::uint64_t n) {
  return format(n == 1 ? "%llu window" : "%llu windows", static_cast<unsigned long long>(n));
}

/// Appends to `out` why each kind of closed window fell short, with the last one's numbers.
void addOutcomeClauses(const CalibrationProgress& p, std::string& out) {
  auto clause = [&out](const std::string& text) { out += "; " + text; };
  auto last = [&p](WindowOutcome o, std::size_t& i) {
    i = static_cast<std::size_t>(o);
    return p.closed[i];
  };
  std::size_t i = 0;
  if (const std::uint64_t n = last(WindowOutcome::kTooSlow, i)) {
    clause(windowsCount(n) + format(" too slow: the last at %.3g rpm, below ~min_speed_rpm = %g",
                                    p.value[i], p.limit[i]));
  }
  if (const std::uint64_t n = last(WindowOutcome::kNotQuasiStatic, i)) {
    clause(windowsCount(n) + format(" not quasi-static: the last at a mesh frequency of %.4g Hz, "
                                    "above ~max_mesh_to_natural x "
                                    "the lowest natural frequency = %.4g Hz",
                                    p.value[i], p.limit[i]));
  }
  if (const std::uint64_t n = last(WindowOutcome::kTooSparse, i)) {
    clause(windowsCount(n) + format(" too sparse: the last read at %.4g Hz, and its second mesh "
                                    "harmonic needs more than %.4g Hz",
                                    p.value[i], p.limit[i]));
  }
  if (const std::uint64_t n = last(WindowOutcome::kIllConditioned, i)) {
    clause(
        windowsCount(n) +
        format(" ill-conditioned: the last one's %.0f readings do not determine the shaft orders",
               p.value[i]));
  }
  if (const std::uint64_t n = last(WindowOutcome::kGated, i)) {
    clause(windowsCount(n) +
           format(" gated: the last one's normalised innovation squared %.3g, above ~gate = %g",
                  p.value[i], p.limit[i]));
  }
}

}  // namespace

CalibrationReport::CalibrationReport(double window_angle, double baseline_torque)
    : baseline_torque_(baseline_torque) {
  progress_.window_angle = window_angle;
}

void CalibrationReport::noteWindow(double torque) {
  progress_.smallest_torque = std::min(progress_.smallest_torque, std::abs(torque));
  if (std::abs(torque) > baseline_torque_) ++progress_.loaded_windows;
}

void CalibrationReport::noteOutcome(WindowOutcome outcome, double value, double limit) {
  const auto i = static_cast<std::size_t>(outcome);
  ++progress_.closed[i];
  progress_.value[i] = value;
  progress_.limit[i] = limit;
}

void CalibrationReport::noteStretch(const SteadyStretch& stretch) {
  keep(progress_, stretch, baseline_torque_);
}

CalibrationProgress CalibrationReport::progress(const SteadyStretch& open) const {
  CalibrationProgress p = progress_;
  keep(p, open, baseline_torque_);
  return p;
}

std::string CalibrationReport::waitingReason(const CalibrationEstimate& estimate,
                                             const SteadyStretch& open) const {
  if (estimate.updates > 0) return {};
  if (estimate.modal_updates > 0) {
    // The natural frequencies have calibrated the bearings; the encoder windows, which the mesh
    // scale and T_p need, still wait.
    return format(estimate.modal_updates == 1
                      ? "%llu record of natural frequencies updated the calibration, the "
                        "encoders' TE not yet: "
                      : "%llu records of natural frequencies updated the calibration, the "
                        "encoders' TE not yet: ",
                  static_cast<unsigned long long>(estimate.modal_updates)) +
           teWaitingReason(estimate, open);
  }
  return teWaitingReason(estimate, open);
}

std::string CalibrationReport::teWaitingReason(const CalibrationEstimate& estimate,
                                               const SteadyStretch& open) const {
  const CalibrationProgress p = progress(open);
  if (p.readings == 0) return "no encoder reading with the gear angle has reached the calibration";
  const double tb = baseline_torque_;
  // A stretch against the window it fell short of: one gear turn of pinion angle, in seconds at
  // the stretch's own mean speed.
  auto shortOf = [&](const SteadyStretch& s, const char* which) {
    std::string out = format(
        "the longest steady %storque (%.3g N*m) lasted %.2f s, %.2f of a gear turn, and a window "
        "needs one gear turn",
        which, s.torque, s.duration, s.angle / p.window_angle);
    const double rpm = std::abs(s.speed) * 60.0 / kTwoPi;
    out += rpm > 0.0 ? format(", %.2f s at %.4g rpm", p.windowSeconds(s.speed), rpm)
                     : std::string(", and the pinion stood still");
    return out;
  };
  const std::string no_unloaded = format(
      "no torque was held at |T| <= ~baseline_torque = %g N*m for the unloaded baseline (the "
      "smallest: %.3g N*m)",
      tb, p.smallest_torque);
  if (estimate.windows == 0) {
    std::string out =
        "no window closed: " + shortOf(nearer(p.unloaded, p.loaded) ? p.unloaded : p.loaded, "");
    if (p.unloaded.readings == 0) out += "; " + no_unloaded;
    return out;
  }
  // Windows closed, none updated: what closed, then why each kind fell short.
  static const char* const kShort[kWindowOutcomes] = {
      "none",     "baseline",         "updated",    "gated",          "before any baseline",
      "too slow", "not quasi-static", "too sparse", "ill-conditioned"};
  std::string counts;
  for (int i = 0; i < kWindowOutcomes; ++i) {
    if (p.closed[i] == 0) continue;
    counts += format("%s%llu %s", counts.empty() ? "" : ", ",
                     static_cast<unsigned long long>(p.closed[i]), kShort[i]);
  }
  std::string out = "no window updated the calibration (" + windowsCount(estimate.windows) +
                    " closed: " + counts + ")";
  auto clause = [&out](const std::string& text) { out += "; " + text; };
  const std::uint64_t unloaded_windows = estimate.windows - p.loaded_windows;
  if (estimate.baseline_windows == 0 && unloaded_windows == 0) {
    clause(p.unloaded.readings > 0
               ? "no unloaded baseline window: " + shortOf(p.unloaded, "unloaded ")
               : no_unloaded);
  }
  if (p.loaded_windows == 0) {
    clause(p.loaded.readings > 0
               ? "no loaded window closed: " + shortOf(p.loaded, "loaded ")
               : format("no torque above ~baseline_torque = %g N*m was held", tb));
  }
  addOutcomeClauses(p, out);
  return out;
}

}  // namespace drivetrain_stiffness

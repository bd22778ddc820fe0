// The calibration's record for its users: the estimate it reports, what it has seen, and why no
// window has updated it, one sentence with the numbers (docs/calibration.md "When no window
// updates"). Fixed size except the sentences.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>

#include "drivetrain_stiffness/calibration/static_te_model.hpp"

namespace drivetrain_stiffness {

/// Why the last window did or did not update the estimate.
enum class WindowOutcome {
  kNone,
  kBaseline,
  kUpdated,
  kGated,
  kNoBaseline,
  kTooSlow,
  kNotQuasiStatic,
  kTooSparse,
  kIllConditioned
};
constexpr int kWindowOutcomes = static_cast<int>(WindowOutcome::kIllConditioned) + 1;
const char* toString(WindowOutcome outcome);

/// The calibration's state after a window (SI; the Calibration message).
struct CalibrationEstimate {
  CalibrationVector value = CalibrationVector::Zero();
  CalibrationVector std = CalibrationVector::Zero();
  CalibrationVector prior_std = CalibrationVector::Zero();
  std::array<bool, kCalibrationSize> identified{};  ///< posterior std below half the prior's
  WindowOutcome outcome = WindowOutcome::kNone;
  bool excited = false;   ///< the last window's excitation sufficed
  bool baseline = false;  ///< a baseline exists
  double nis = 0.0;       ///< of the last loaded window (3 dof)
  /// Per feature, the model error the windows show over the allowance (ModelErrorScale::scale).
  FeatureVector model_error_scale = FeatureVector::Ones();
  std::uint64_t windows = 0, baseline_windows = 0, updates = 0, gated = 0, not_excited = 0;
  /// Records of identified natural frequencies that update the estimate, and that the gate refuses.
  std::uint64_t modal_updates = 0, modal_gated = 0;
  double modal_nis = 0.0;      ///< of the last record of natural frequencies (dof: its count)
  double window_torque = 0.0;  ///< [N·m] the last window's mean
  double window_speed = 0.0;   ///< [rad/s] the last window's mean pinion speed
  FeatureVector measured = FeatureVector::Zero(), predicted = FeatureVector::Zero(),
                feature_std = FeatureVector::Zero();
  double series_compliance = 0.0,
         series_compliance_std = 0.0;  ///< [m/N] mean TE / F at ~reference_torque
  double mesh_stiffness = 0.0, mesh_stiffness_low = 0.0,
         mesh_stiffness_high = 0.0;  ///< [N/m] at the window torque, 95 % bounds
  std::array<double, 2> bearing_stiffness{}, bearing_stiffness_low{},
      bearing_stiffness_high{};  ///< [N/m] per shaft
  std::array<double, 3> natural_frequency{}, natural_frequency_low{},
      natural_frequency_high{};  ///< [Hz]
  double knee_torque = 0.0;      ///< [N·m] where the back half lifts
};

/// A stretch of readings at a steady torque that did not become a window (dropped or still open).
struct SteadyStretch {
  long readings = 0;
  double duration = 0.0;  ///< [s]
  double angle = 0.0;     ///< [rad] of pinion angle spanned
  double torque = 0.0;    ///< [N·m] mean held torque
  double speed = 0.0;     ///< [rad/s] mean pinion speed
};

/// What the calibration has seen, for Calibrator::waitingReason; fixed size.
struct CalibrationProgress {
  std::uint64_t readings = 0;  ///< readings with the gear angle
  double window_angle = 0.0;   ///< [rad] of pinion angle a window spans: one gear turn
  /// The longest unloaded and loaded stretches (by angle, then time); readings == 0: none.
  SteadyStretch unloaded, loaded;
  /// [N·m] the smallest mean |torque| of any stretch or closed window.
  double smallest_torque = std::numeric_limits<double>::infinity();
  std::uint64_t loaded_windows = 0;                     ///< closed above ~baseline_torque
  std::array<std::uint64_t, kWindowOutcomes> closed{};  ///< closed windows per WindowOutcome
  /// Per WindowOutcome, the number that decided its last window and its limit (docs/calibration.md
  /// "When no window updates").
  std::array<double, kWindowOutcomes> value{}, limit{};
  std::uint64_t count(WindowOutcome o) const { return closed[static_cast<std::size_t>(o)]; }
  /// [s] one window at pinion speed [rad/s]; infinite at rest.
  double windowSeconds(double speed) const;
};

class CalibrationReport {
 public:
  /// Records windows of `window_angle` [rad] of pinion angle, unloaded at |T| <= baseline_torque.
  CalibrationReport(double window_angle, double baseline_torque);

  /// Counts one reading with the gear angle.
  void noteReading() { ++progress_.readings; }
  /// Records a closed window's mean torque [N·m]: the smallest torque, the loaded windows.
  void noteWindow(double torque);
  /// Records a closed window's outcome, the number that decided it and its limit.
  void noteOutcome(WindowOutcome outcome, double value, double limit);
  /// Keeps a stretch that did not become a window if it came nearer than the kept one.
  void noteStretch(const SteadyStretch& stretch);
  /// What the calibration has seen, with the open window's stretch `open`. Allocation-free.
  CalibrationProgress progress(const SteadyStretch& open) const;
  /// Calibrator::waitingReason of `estimate` with the open window's stretch `open`. Allocates.
  std::string waitingReason(const CalibrationEstimate& estimate, const SteadyStretch& open) const;

 private:
  /// waitingReason's sentence about the encoder windows alone.
  std::string teWaitingReason(const CalibrationEstimate& estimate, const SteadyStretch& open) const;

  CalibrationProgress progress_;
  double baseline_torque_ = 0.0;  ///< [N·m] ~baseline_torque
};

}  // namespace drivetrain_stiffness

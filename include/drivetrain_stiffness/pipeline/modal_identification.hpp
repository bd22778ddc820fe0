// One accelerometer record's output-only modal identification as the pipeline runs it: shaft and
// mesh orders removed with the measured angle, SSI-COV with standard deviations, automatic pole
// selection, matching to the model's modes (docs/vibration.md "Identification in the pipeline").
// ROS-free and a pure function of its job: it runs on any thread with the same bits.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "drivetrain_stiffness/modal/mode_matching.hpp"
#include "drivetrain_stiffness/modal/pole_selection.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"

namespace drivetrain_stiffness {

/// A model mode as the identification compares with it.
struct ModelModePrediction {
  std::string dominant;          ///< "x_p", "x_g" or "x"
  double frequency = 0.0;        ///< [Hz] undamped natural frequency
  double low = 0.0, high = 0.0;  ///< [Hz] 95 % band (equal to frequency when not calibrated)
  Eigen::Vector3d shape = Eigen::Vector3d::Zero();  ///< over (x_p, x_g, x) [-]
};

/// What one identification reads: a copy of the record and the model at the record's end.
struct ModalJob {
  Eigen::MatrixXd record;    ///< columns x frames [m/s^2], signs applied
  Eigen::VectorXd angle;     ///< [rad] unwrapped pinion angle at each frame
  double sample_rate = 0.0;  ///< [Hz]
  Stamp start, end;          ///< the first and the last frame
  double torque = 0.0;       ///< [N*m] held pinion torque at the end
  std::vector<std::string> channels;
  std::vector<int> channel_shaft;  ///< per column: 0 pinion (x_p), 1 gear (x_g)
  std::array<ModelModePrediction, 3> predicted;
  int pinion_teeth = 0, gear_teeth = 0;
  int max_order = 20;     ///< SSI-COV's last model order (even)
  int block_rows = 40;    ///< SSI-COV's block rows i (lags 1 to 2i - 1)
  int skipped_lags = 32;  ///< SSI-COV's Hankel starts at lag skipped_lags + 1
  double band = 0.35;     ///< the flat band as a fraction of sample_rate: poles above set aside
};

/// One pole of one model order, for the stabilisation diagram.
struct ModalPoleRow {
  int order = 0;
  double frequency = 0.0, damping = 0.0;          ///< [Hz], [-]
  double frequency_std = 0.0, damping_std = 0.0;  ///< [Hz], [-]; NaN without std
  modal::PoleStatus status = modal::PoleStatus::kUnstable;
  int mode = -1;  ///< the identified mode its cluster became, or -1
};

/// One record's identification (the modal_identification message).
struct ModalReport {
  Stamp start, end;
  double duration = 0.0;      ///< [s]
  double sample_rate = 0.0;   ///< [Hz]
  double torque = 0.0;        ///< [N*m]
  double pinion_speed = 0.0;  ///< [rad/s] mean over the record
  std::vector<std::string> channels;
  std::vector<modal::IdentifiedMode> modes;  ///< by frequency
  std::vector<int> model_mode;               ///< per mode: index into predicted, or -1
  std::vector<double> mac;                   ///< per mode: with its model mode; 0 when none
  std::array<ModelModePrediction, 3> predicted;
  std::array<modal::Observability, 3> observability{};
  std::array<int, 3> identified{-1, -1, -1};      ///< per model mode: index into modes, or -1
  std::vector<modal::FrequencyBand> order_bands;  ///< removed orders: poles there set aside
  std::vector<ModalPoleRow> poles;
  int spurious_clusters = 0;

  /// One sentence on identified mode `i`: "measured 8398 ± 3 Hz (1 sigma) where the model
  /// predicts 9377 Hz (x_p)".
  std::string statement(std::size_t i) const;
  /// One sentence on model mode `k`: identified, not identified, or why it is not observable.
  std::string modelStatement(std::size_t k) const;
};

/// Identifies `job`'s record. Throws InvalidInput (naming the field) for a record the method
/// cannot identify, e.g. fewer samples than its lags and blocks need.
ModalReport identifyModes(const ModalJob& job);

}  // namespace drivetrain_stiffness

// Simulated accelerometers of a rig scenario: the 3-DOF model's transverse accelerations x_p'' and
// x_g'' (docs/vibration.md "Simulated accelerometers"). ROS-free and deterministic for a seed.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/core/dynamics/speed_profile.hpp"
#include "scenarios/rig_scenarios.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {

struct VibrationSpec {
  double rate = 51200.0;    ///< [Hz] output sample rate; 0: no vibration
  int block = 1024;         ///< samples per VibrationBlock
  int oversample = 8;       ///< the internal rate is oversample x rate
  double roughness = 1e-7;  ///< [m] rms of the random mesh displacement per internal sample
  double noise = 0.005;     ///< [m/s^2] rms of the sensor noise per output sample
  std::uint64_t seed = 1;   ///< seeds the roughness and the sensor noise
};

/// The record: whole blocks of two channels, interleaved by sample.
struct VibrationRecord {
  double rate = 0.0;                    ///< [Hz]
  int block = 0;                        ///< samples per block
  std::array<std::string, 2> channels;  ///< the pinion's, then the gear's support name
  std::vector<float> data;              ///< [m/s^2] data[i * 2 + c]
  std::size_t samples() const { return data.size() / 2; }
};

/// The anti-alias low-pass at the internal rate (odd length, linear phase, unit DC gain): a Kaiser-
/// windowed sinc, cutoff 0.4 x the output rate, stop band from 0.45 x the output rate at 100 dB.
/// Throws InvalidInput unless 2 <= oversample <= 16.
std::vector<double> antiAliasFilter(int oversample);

/// One knot of the true pinion torque, linear between knots and held outside them.
struct TorqueKnot {
  double t = 0.0;       ///< [s]
  double torque = 0.0;  ///< [N*m]
};

/// The torque knots of a scenario's events: the torque samples a rig's sensor passes (finite, about
/// the pinion, on the running clock, below 1e3 N*m); the injected faults are left out.
std::vector<TorqueKnot> scenarioTorque(const std::vector<RigEvent>& events);

/// The accelerations of the pinion and gear shafts along the line of action over [0, duration)
/// [s] under the pinion torque `torque` (at least one knot) and pinion speed `speed`. Throws
/// InvalidInput naming the field of `spec` or the rig (dynamics block, supports).
VibrationRecord simulateVibration(const RigConfig& rig, const std::vector<TorqueKnot>& torque,
                                  const SpeedProfile& speed, double duration,
                                  const VibrationSpec& spec);

}  // namespace drivetrain_stiffness

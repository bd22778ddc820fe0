// Stepped-sine torque sweep of the rig model (seed 000 section 4.2): docs/resonance.md, docs/cli.md
// "sweep".
#pragma once

#include <array>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/spectral/spectrum.hpp"

namespace drivetrain_stiffness {

enum class SweepDirection { kUp, kDown, kBoth };
const char* toString(SweepDirection d);
/// "up", "down" or "both"; throws InvalidInput naming `field` otherwise.
SweepDirection parseSweepDirection(const std::string& field, const std::string& text);

struct SweepSpec {
  double start = 60.0, stop = 3000.0,
         step = 60.0;                    ///< [Hz]
  double torque_amplitude = 0.05;        ///< [N·m]
  double settle = 0.01, measure = 0.05;  ///< [s]; measure rounded up to whole periods
  Fidelity fidelity = Fidelity::kFull;
  bool include_te = true;  ///< keep the rig's manufacturing TE
  SweepDirection direction = SweepDirection::kUp;
};

struct SweepOutput {
  std::vector<double> frequency;                   ///< [Hz]
  std::array<std::vector<double>, 3> rms;          ///< [m] x_p, x_g, x about their means
  std::array<std::vector<SpectralPeak>, 3> peaks;  ///< top three per coordinate
  std::array<std::vector<double>, 3> rms_down;     ///< [m] ascending; kBoth only
  /// The top three lines of the first direction's record per coordinate (seed 000 Fig 8b, d, f);
  /// empty beyond 4 Mi samples.
  std::array<std::vector<SpectralPeak>, 3> spectrum_peaks;
  double spectrum_resolution = 0.0;  ///< [Hz]
  double sample_interval = 0.0;      ///< [s]
};

/// start + i step [Hz] for i = 0 .. floor((stop - start) / step + 1e-9). Throws InvalidInput naming
/// `field` unless step > 0 and stop >= start.
std::vector<double> frequencyGrid(const std::string& field, double start, double stop, double step);

/// max_i |a_i - b_i| / max(a_i, b_i) over the points where the max is positive, else 0: near 1 an
/// up and a down sweep on two branches. Throws InvalidInput unless a, b >= 0 of equal sizes.
double largestRelativeDifference(const std::vector<double>& a, const std::vector<double>& b);

/// The sweep on the rig, its bearings' stiffness at the mean torque. Throws InvalidInput without a
/// dynamics block or for a bad spec, naming the field.
SweepOutput torqueSweep(const RigConfig& rig, const SweepSpec& spec);

}  // namespace drivetrain_stiffness

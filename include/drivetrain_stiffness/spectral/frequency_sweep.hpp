// Frequency sweep of the rig model (seed 000 section 4.2): a sine torque fluctuation stepped over
// frequency; at each frequency the model runs to steady state (`settle` seconds, discarded) and the
// RMS of each coordinate about its mean is taken over `measure` seconds. The state and time carry
// over from one frequency to the next (a stepped-sine sweep), so an up and a down sweep can land on
// different branches of a nonlinear response: the jumps of seed 000 section 4.2 and of Kahraman &
// Singh. The whole up-sweep record is also transformed (FFTW) per coordinate, as the seed's Fig 8.
// Peaks of the RMS curves are refined below the frequency step (spectrum.hpp). In the linear cases
// they fall on the modal frequencies within the step (test_frequency_sweep.cpp).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/reduced_models.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"
#include "drivetrain_stiffness/spectral/spectrum.hpp"

namespace drivetrain_stiffness {

enum class SweepDirection { kUp, kDown, kBoth };
const char* toString(SweepDirection d);
/// "up", "down" or "both"; anything else throws InvalidInput naming `field` and every accepted
/// name.
SweepDirection parseSweepDirection(const std::string& field, const std::string& text);

struct SweepSpec {
  double start = 60.0, stop = 3000.0,
         step = 60.0;                    ///< [Hz] (seed 000 section 4.2: 0-3 kHz in 60 Hz steps)
  double torque_amplitude = 0.05;        ///< [N·m] of the fluctuation
  double settle = 0.01, measure = 0.05;  ///< [s]; measure is rounded up to whole periods
  Fidelity fidelity = Fidelity::kFull;   ///< kFull integrates with dopri5 (events)
  bool include_te = true;                ///< keep the rig's manufacturing TE
  SweepDirection direction = SweepDirection::kUp;  ///< kBoth: up, then down from the last state
};

struct SweepOutput {
  std::vector<double> frequency;                   ///< [Hz]
  std::array<std::vector<double>, 3> rms;          ///< x_p, x_g, x about their means [m]
  std::array<std::vector<SpectralPeak>, 3> peaks;  ///< top three per coordinate
  /// Down sweep, in the same (ascending) frequency order; empty unless direction is kBoth.
  std::array<std::vector<double>, 3> rms_down;
  /// Amplitude spectrum of the whole first-direction record per coordinate (seed 000 Fig 8b, d, f):
  /// its top three peaks, and the bin spacing [Hz]. Only lines present throughout the record (the
  /// mesh frequency and its harmonics) have meaningful heights: each sweep tone is there only for
  /// its dwell, so its height depends on the dwell and on where it sits under the Hann taper.
  /// Empty when the record would exceed 4 Mi samples.
  std::array<std::vector<SpectralPeak>, 3> spectrum_peaks;
  double spectrum_resolution = 0.0;
  double sample_interval = 0.0;  ///< common output step of the record [s]
};

/// The stepped grid start, start + step, ... up to stop (included when (stop - start) / step is
/// whole within 1e-9): start + i step for i = 0 .. floor((stop - start) / step + 1e-9), each point
/// computed from i, so no rounding accumulates along the grid. Needs step > 0 and stop >= start
/// (InvalidInput naming `field` otherwise).
std::vector<double> frequencyGrid(const std::string& field, double start, double stop, double step);

/// The largest disagreement of two responses on the same grid, relative to the larger of each
/// pair: max_i |a_i - b_i| / max(a_i, b_i) over the points where that maximum is positive, 0 when
/// there is none (a, b >= 0, equal sizes: InvalidInput otherwise). Up against down sweep: a value
/// near 0 is one branch; a large one (up to 1) is a jump between two branches of a nonlinear
/// response (seed 000 section 4.2).
double largestRelativeDifference(const std::vector<double>& a, const std::vector<double>& b);

/// Runs the sweep on the rig (needs a dynamics block); bearing stiffness from the bearing model at
/// the rig's mean torque.
SweepOutput torqueSweep(const RigConfig& rig, const SweepSpec& spec);

}  // namespace drivetrain_stiffness

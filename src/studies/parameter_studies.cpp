// Seed 000 parameter studies (sections 4.1-4.3). The ranges are the seed's:
//   Fig 4  bearing radial stiffness over inner x outer shrink range 2e-3..8e-3 mm (section 4.1)
//   Fig 5  bearing radial stiffness over axial x radial preload 400..2000 N (section 4.1)
//   Fig 9  RMS of x_p, x_g, x over the 0-3 kHz torque sweep in 60 Hz steps (section 4.2)
//   Fig 10 resonances vs outer shrink range 0.001..0.01 mm in 5e-4 mm steps, inner 0.005 mm,
//          radial and axial preload 1 kN (section 4.3.1)
//   Fig 11 resonances vs radial preload 200..2000 N in 100 N steps, shrink range 0.005 mm,
//          axial preload 1.2 kN (section 4.3.2)
// "Shrink range" is read as the diametral interference (the seed's eq 9-10 use the diametral
// interference; docs/bearing_model.md), so 0.005 mm -> 5e-6 m.
#include "drivetrain_stiffness/studies/parameter_studies.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>

#include "drivetrain_stiffness/core/resonance/modal_analysis.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"

namespace drivetrain_stiffness {
namespace {

/// Inclusive grid start, start + step, ..., stop (rounded count, so 1e-6..1e-5 by 5e-7 has 19
/// points).
std::vector<double> grid(double start, double stop, double step) {
  const int n = static_cast<int>(std::lround((stop - start) / step)) + 1;
  std::vector<double> g(n);
  for (int i = 0; i < n; ++i) g[i] = start + i * step;
  return g;
}

/// The settings applied to every support (the seed's two bearings are equal, section 4).
struct Settings {
  double axial = 0.0, radial = 0.0, inner = 0.0, outer = 0.0;
};

/// Rig state at `s`: the estimator at the rig's mean torque (the mesh force adds to the radial
/// preload as on the rig).
const StiffnessEstimate& solveAt(StiffnessEstimator& estimator, const RigConfig& rig,
                                 const Settings& s) {
  std::vector<PreloadSetting> settings;
  for (const BearingSupportConfig& b : rig.bearings)
    settings.push_back({b.name, s.axial, s.radial, s.inner, s.outer});
  estimator.setPreloads(settings);
  return estimator.setTorque(rig.dynamics.present ? rig.dynamics.torque : 0.0);
}

Settings configured(const RigConfig& rig) {
  const BearingSupportConfig& b = rig.bearings.front();
  return {b.axial_preload, b.radial_preload, b.interference.inner, b.interference.outer};
}

StudyTable bearingSurface(const RigConfig& rig, bool shrink) {
  StudyTable t;
  StiffnessEstimator estimator(rig);
  Settings s = configured(rig);
  if (shrink) {
    t = {"bearing_shrink",
         "seed 000 Fig 4",
         "surface",
         {"inner_interference_m", "outer_interference_m", "radial_stiffness_N_per_m"},
         {}};
    for (double inner : grid(2e-6, 8e-6, 5e-7))
      for (double outer : grid(2e-6, 8e-6, 5e-7)) {
        s.inner = inner;
        s.outer = outer;
        t.rows.push_back(
            {inner, outer, solveAt(estimator, rig, s).supports.front().solution.radialStiffness()});
      }
  } else {
    t = {"bearing_preload",
         "seed 000 Fig 5",
         "surface",
         {"axial_preload_N", "radial_preload_N", "radial_stiffness_N_per_m"},
         {}};
    for (double axial : grid(400.0, 2000.0, 100.0))
      for (double radial : grid(400.0, 2000.0, 100.0)) {
        s.axial = axial;
        s.radial = radial;
        t.rows.push_back({axial, radial,
                          solveAt(estimator, rig, s).supports.front().solution.radialStiffness()});
      }
  }
  return t;
}

/// Natural frequencies at the mean composite mesh stiffness (the linear modes of seed 000 eq 15-18)
/// with the bearing stiffness of each shaft summed over its supports.
std::vector<double> resonanceRow(double x, StiffnessEstimator& estimator, const RigConfig& rig,
                                 const Settings& s) {
  solveAt(estimator, rig, s);
  const std::array<double, 2> kb = estimator.shaftRadialStiffness();
  const double km = meanMeshStiffness(estimator.mesh());
  const std::array<Mode, 3> modes =
      modalAnalysis(rigRotorParameters(rig, estimator.mesh(), kb), km);
  std::vector<double> row{x, kb[0], kb[1], km};
  for (const Mode& m : modes) row.push_back(m.natural_frequency);
  for (const Mode& m : modes)
    row.push_back(m.dominant == "x_p" ? 0.0 : m.dominant == "x_g" ? 1.0 : 2.0);
  return row;
}

const std::vector<std::string> kResonanceColumns{"pinion_bearing_stiffness_N_per_m",
                                                 "gear_bearing_stiffness_N_per_m",
                                                 "mean_mesh_stiffness_N_per_m",
                                                 "f1_hz",
                                                 "f2_hz",
                                                 "f3_hz",
                                                 "f1_dominant",
                                                 "f2_dominant",
                                                 "f3_dominant"};

StudyTable resonanceStudy(const RigConfig& rig, bool shrink) {
  if (!rig.dynamics.present)
    throw InvalidInput("resonance studies need a 'dynamics:' block (masses, inertias)");
  StiffnessEstimator estimator(rig);
  StudyTable t;
  std::vector<std::string> columns{shrink ? "outer_interference_m" : "radial_preload_N"};
  columns.insert(columns.end(), kResonanceColumns.begin(), kResonanceColumns.end());
  if (shrink) {
    t = {"resonance_shrink", "seed 000 Fig 10", "curves", columns, {}};
    for (double outer : grid(1e-6, 1e-5, 5e-7))
      t.rows.push_back(resonanceRow(outer, estimator, rig, {1000.0, 1000.0, 5e-6, outer}));
  } else {
    t = {"resonance_preload", "seed 000 Fig 11", "curves", columns, {}};
    for (double radial : grid(200.0, 2000.0, 100.0))
      t.rows.push_back(resonanceRow(radial, estimator, rig, {1200.0, radial, 5e-6, 5e-6}));
  }
  return t;
}

StudyTable rmsSweep(const RigConfig& rig) {
  if (!rig.dynamics.present)
    throw InvalidInput("rms_sweep needs a 'dynamics:' block (masses, inertias)");
  const SweepOutput sweep =
      torqueSweep(rig, SweepSpec{});  // seed 000 section 4.2: 60..3000 Hz by 60 Hz
  StudyTable t{"rms_sweep",
               "seed 000 Fig 9",
               "curves",
               {"frequency_hz", "rms_x_p_m", "rms_x_g_m", "rms_x_m"},
               {}};
  for (std::size_t i = 0; i < sweep.frequency.size(); ++i)
    t.rows.push_back({sweep.frequency[i], sweep.rms[0][i], sweep.rms[1][i], sweep.rms[2][i]});
  return t;
}

}  // namespace

const std::vector<std::string>& studyNames() {
  static const std::vector<std::string> names{"bearing_shrink", "bearing_preload", "rms_sweep",
                                              "resonance_shrink", "resonance_preload"};
  return names;
}

StudyTable runStudy(const std::string& name, const RigConfig& rig) {
  if (rig.bearings.empty())
    throw InvalidInput("bearings: the studies need at least one bearing support");
  if (name == "bearing_shrink") return bearingSurface(rig, true);
  if (name == "bearing_preload") return bearingSurface(rig, false);
  if (name == "rms_sweep") return rmsSweep(rig);
  if (name == "resonance_shrink") return resonanceStudy(rig, true);
  if (name == "resonance_preload") return resonanceStudy(rig, false);
  std::string known;
  for (const std::string& n : studyNames()) known += (known.empty() ? "" : ", ") + n;
  throw InvalidInput("study = '" + name + "': unknown (known: " + known + ")");
}

void writeStudyCsv(const StudyTable& table, const std::string& path) {
  std::ofstream csv(path);
  if (!csv) throw InvalidInput("--out: cannot write '" + path + "'");
  csv << std::setprecision(std::numeric_limits<double>::max_digits10);
  for (std::size_t c = 0; c < table.columns.size(); ++c) csv << (c ? "," : "") << table.columns[c];
  csv << '\n';
  for (const std::vector<double>& row : table.rows) {
    for (std::size_t c = 0; c < row.size(); ++c) csv << (c ? "," : "") << row[c];
    csv << '\n';
  }
  if (!csv) throw InvalidInput("--out: write failed for '" + path + "'");
}

}  // namespace drivetrain_stiffness

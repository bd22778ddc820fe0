#include "finite_checks.hpp"

#include <cmath>
#include <string>

#include "fuzz_target.hpp"

namespace drivetrain_stiffness::fuzz {
namespace {

void check(const std::string& field, double value) {
  if (!std::isfinite(value))
    throw FuzzFinding("non-finite output " + field + " = " + std::to_string(value));
}

template <typename Matrix>
void checkMatrix(const std::string& field, const Matrix& m) {
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      check(field + "(" + std::to_string(i) + "," + std::to_string(j) + ")", m(i, j));
    }
  }
}

}  // namespace

void requireAllFinite(const StiffnessEstimate& e) {
  check("stiffness.torque", e.torque);
  check("stiffness.mesh_force", e.mesh_force);
  check("stiffness.mesh.phase", e.mesh.phase);
  check("stiffness.mesh.mean", e.mesh.mean);
  check("stiffness.mesh.current.k1", e.mesh.current.k1);
  check("stiffness.mesh.current.k2", e.mesh.current.k2);
  check("stiffness.mesh.current.k_chain", e.mesh.current.k_chain);
  check("stiffness.mesh.current.composite", e.mesh.current.composite);
  for (const SupportEstimate& s : e.supports) {
    const std::string f = "stiffness.supports[" + s.name + "].";
    check(f + "radial_load", s.radial_load);
    check(f + "axial_load", s.axial_load);
    checkMatrix(f + "solution.displacement", s.solution.displacement);
    checkMatrix(f + "solution.load", s.solution.load);
    checkMatrix(f + "solution.stiffness", s.solution.stiffness);
    check(f + "solution.residual", s.solution.residual);
    check(f + "solution.max_contact_pressure", s.solution.max_contact_pressure);
    for (const auto& row : s.solution.rows) {
      for (const BallState& b : row) {
        check(f + "ball.azimuth", b.azimuth);
        check(f + "ball.contact_angle", b.contact_angle);
        check(f + "ball.deflection", b.deflection);
        check(f + "ball.load", b.load);
        check(f + "ball.max_pressure", b.max_pressure);
      }
    }
  }
}

void requireAllFinite(const DynamicsSample& s) {
  check("te.t", s.t);
  checkMatrix("te.state", s.state);
  check("te.dynamic_te", s.dynamic_te);
  check("te.static_te", s.static_te);
  check("te.mesh_force", s.mesh_force);
  check("te.phase", s.phase);
  check("te.torque", s.torque);
}

void requireAllFinite(const ResonanceEstimate& r) {
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const std::string f = "resonance.modes[" + std::to_string(i) + "].";
    check(f + "natural_frequency", r.modes[i].natural_frequency);
    check(f + "damped_frequency", r.modes[i].damped_frequency);
    check(f + "damping_ratio", r.modes[i].damping_ratio);
    checkMatrix(f + "shape", r.modes[i].shape);
  }
  check("resonance.floquet_margin", r.floquet_margin);
}

void requireAllFinite(const SpectrumPeaks& peaks) {
  if (peaks.count > SpectrumPeaks::kMaxPeaks)
    throw FuzzFinding("spectrum.count beyond its storage");
  for (std::size_t i = 0; i < peaks.count; ++i) {
    check("spectrum.peak.frequency", peaks.peaks[i].frequency);
    check("spectrum.peak.amplitude", peaks.peaks[i].amplitude);
  }
  check("spectrum.resolution", peaks.resolution);
  check("spectrum.window_s", peaks.window_seconds);
}

void requireAllFinite(const CalibrationBands& b) {
  for (double v : {b.mesh_stiffness, b.mesh_stiffness_low, b.mesh_stiffness_high})
    check("bands.mesh_stiffness", v);
  for (int i = 0; i < 2; ++i) {
    for (double v :
         {b.bearing_stiffness[i], b.bearing_stiffness_low[i], b.bearing_stiffness_high[i]})
      check("bands.bearing_stiffness", v);
  }
  for (int i = 0; i < 3; ++i) {
    for (double v :
         {b.natural_frequency[i], b.natural_frequency_low[i], b.natural_frequency_high[i]})
      check("bands.natural_frequency", v);
  }
}

void FiniteSink::stiffness(Stamp, const StiffnessEstimate& estimate,
                           const CalibrationBands& bands) {
  requireAllFinite(estimate);
  requireAllFinite(bands);
  ++outputs;
}
void FiniteSink::transmissionError(Stamp stamp, const DynamicsSample& sample,
                                   const SampleContext& context) {
  requireAllFinite(sample);
  check("te.context.pinion_angle", context.pinion_angle);
  if (context.resonance) requireAllFinite(*context.resonance);
  // The documented contract of the sample stamp (rig_pipeline.hpp): sample.t is exactly the stamp.
  if (sample.t != stamp.toSec()) throw FuzzFinding("te.t differs from its stamp");
  ++outputs;
}
void FiniteSink::spectrum(Stamp, const SpectrumPeaks& peaks) {
  requireAllFinite(peaks);
  ++outputs;
}
void FiniteSink::resonance(Stamp, const ResonanceEstimate& estimate,
                           const CalibrationBands& bands) {
  requireAllFinite(estimate);
  requireAllFinite(bands);
  ++outputs;
}
// The calibration's and the mesh-period outputs (the calibration rule, the per-period statistics):
// every number a message would carry, so "never a NaN on a topic" holds for them under hostile
// input too.
void FiniteSink::measuredTe(Stamp, const MeasuredTeSample& s) {
  check("measured_te.te", s.te);
  check("measured_te.predicted", s.predicted);
  check("measured_te.residual", s.residual);
  check("measured_te.torque", s.torque);
  check("measured_te.phase", s.phase);
  ++outputs;
}
void FiniteSink::calibration(Stamp, const CalibrationEstimate& e) {
  checkMatrix("calibration.value", e.value);
  checkMatrix("calibration.std", e.std);
  checkMatrix("calibration.measured", e.measured);
  checkMatrix("calibration.predicted", e.predicted);
  checkMatrix("calibration.feature_std", e.feature_std);
  for (double v :
       {e.nis, e.window_torque, e.window_speed, e.series_compliance, e.series_compliance_std,
        e.mesh_stiffness, e.mesh_stiffness_low, e.mesh_stiffness_high, e.knee_torque}) {
    check("calibration.scalar", v);
  }
  for (int i = 0; i < 2; ++i) {
    check("calibration.bearing_stiffness", e.bearing_stiffness[i]);
    check("calibration.bearing_stiffness_low", e.bearing_stiffness_low[i]);
    check("calibration.bearing_stiffness_high", e.bearing_stiffness_high[i]);
  }
  for (int i = 0; i < 3; ++i) {
    check("calibration.natural_frequency", e.natural_frequency[i]);
    check("calibration.natural_frequency_low", e.natural_frequency_low[i]);
    check("calibration.natural_frequency_high", e.natural_frequency_high[i]);
  }
  ++outputs;
}
void FiniteSink::meshPeriod(Stamp, const MeshPeriodStatistics& s) {
  for (double v : {s.duration, s.te_mean, s.te_rms, s.te_peak_to_peak, s.mesh_force_mean,
                   s.mesh_force_rms, s.mesh_force_peak_to_peak, s.mesh_frequency, s.torque}) {
    check("mesh_period_stats", v);
  }
  ++outputs;
}

void FiniteSink::modalIdentification(Stamp, const ModalReport& r) {
  // The standard deviations may be NaN (not computed: the message carries 0); the rest is finite.
  for (double v : {r.duration, r.sample_rate, r.torque, r.pinion_speed})
    check("modal_identification", v);
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    check("modal_identification.modes.frequency", r.modes[i].frequency);
    check("modal_identification.modes.damping", r.modes[i].damping);
  }
  for (double mac : r.mac) check("modal_identification.modes.mac", mac);
  for (const ModelModePrediction& p : r.predicted) {
    for (double v : {p.frequency, p.low, p.high}) check("modal_identification.predicted", v);
  }
  for (const ModalPoleRow& p : r.poles) {
    check("modal_identification.pole_frequency", p.frequency);
    check("modal_identification.pole_damping", p.damping);
  }
  ++outputs;
}

}  // namespace drivetrain_stiffness::fuzz

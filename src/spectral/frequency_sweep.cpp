#include "drivetrain_stiffness/spectral/frequency_sweep.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/scenes.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {
constexpr double kTwoPi = 6.283185307179586;
}

SweepOutput torqueSweep(const RigConfig& rig, const SweepSpec& spec) {
  if (!rig.dynamics.present) throw InvalidInput("sweep: the gearbox file has no 'dynamics:' block");
  requirePositive("sweep.start", spec.start);
  requirePositive("sweep.step", spec.step);
  if (!(spec.stop >= spec.start)) throwInvalid("sweep.stop", spec.stop, "must be >= sweep.start");
  requirePositive("sweep.settle", spec.settle);
  requirePositive("sweep.measure", spec.measure);
  requireFinite("sweep.torque_amplitude", spec.torque_amplitude);
  const DynamicsConfig& d = rig.dynamics;
  auto mesh = std::make_shared<AntiBacklashMesh>(rig.gears, rig.anti_backlash, rig.mesh_model, rig.mesh_samples);
  StiffnessEstimator estimator(rig);
  const StiffnessEstimate& e = estimator.setTorque(d.torque);
  std::array<double, 2> kb{{0.0, 0.0}};
  for (std::size_t i = 0; i < e.supports.size(); ++i) kb[rig.bearings[i].shaft] += e.supports[i].solution.radialStiffness();
  const GearRotorParameters p = rigRotorParameters(rig, *mesh, kb);

  SweepOutput out;
  const long n = static_cast<long>(std::floor((spec.stop - spec.start) / spec.step + 1e-9));
  for (long i = 0; i <= n; ++i) {
    const double f = spec.start + i * spec.step;
    RigExcitationSpec ex;
    ex.speed = d.speed_rpm * kTwoPi / 60.0;
    ex.te_amplitude = spec.include_te ? d.transmission_error_amplitude : 0.0;
    ex.backlash = d.backlash;
    ex.torque.kind = TorqueProfile::Kind::kSine;
    ex.torque.mean = d.torque;
    ex.torque.amplitude = spec.torque_amplitude;
    ex.torque.frequency = f;
    const auto excitation = std::make_shared<RigExcitation>(mesh, p, ex);
    const GearRotorModel model(p, excitation);
    // Sample at least 20 times per excitation period, on a divisor of the mesh period.
    const double mesh_period = 1.0 / excitation->meshFrequency();
    const double per_period = std::max(32.0, std::ceil(20.0 * f * mesh_period));
    const double dt = mesh_period / per_period;
    const double duration = std::ceil((spec.settle + spec.measure) / dt) * dt;
    std::array<double, 3> sum{}, sum2{};
    long count = 0;
    const Observer observe = [&](double t, const State6& y) {
      if (t < duration - spec.measure) return;
      for (int c = 0; c < 3; ++c) {
        sum[c] += y[c];
        sum2[c] += y[c] * y[c];
      }
      ++count;
    };
    const State6 y0 = staticEquilibrium(model, 0.0);
    if (spec.fidelity == Fidelity::kFull) {
      IntegratorOptions o;
      o.relative_tolerance = 1e-8;
      o.absolute_tolerance = 1e-15;
      o.max_step = dt;
      integrate(model, IntegratorMethod::kDopri5, o, 0.0, y0, duration, dt, observe);
    } else {
      integrateReduced(model, spec.fidelity, 0.0, y0, duration, dt, observe);
    }
    out.frequency.push_back(f);
    for (int c = 0; c < 3; ++c) {
      const double mean = sum[c] / count;
      out.rms[c].push_back(std::sqrt(std::max(sum2[c] / count - mean * mean, 0.0)));
    }
  }
  if (out.frequency.size() >= 3) {
    for (int c = 0; c < 3; ++c) out.peaks[c] = curvePeaks(out.frequency, out.rms[c], 3);
  }
  return out;
}

}  // namespace drivetrain_stiffness

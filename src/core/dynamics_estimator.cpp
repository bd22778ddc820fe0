#include "drivetrain_stiffness/core/dynamics_estimator.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/scenes.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
DynamicsEstimator::DynamicsEstimator(const RigConfig& rig, const std::array<double, 2>& bearing_stiffness,
                                     double output_rate)
    : DynamicsEstimator(rig, bearing_stiffness, output_rate,
                        std::make_shared<const AntiBacklashMesh>(rig.gears, rig.anti_backlash, rig.mesh_model, rig.mesh_samples)) {}

DynamicsEstimator::DynamicsEstimator(const RigConfig& rig, const std::array<double, 2>& bearing_stiffness,
                                     double output_rate, std::shared_ptr<const AntiBacklashMesh> mesh)
    : rig_(rig), bearing_stiffness_(bearing_stiffness), requested_rate_(output_rate), torque_(std::make_shared<double>(0.0)),
      mesh_(std::move(mesh)) {
  if (!rig.dynamics.present) throw InvalidInput("dynamics: the gearbox file has no 'dynamics:' block");
  requirePositive("output_rate", output_rate);
  for (int i = 0; i < 2; ++i) requireNonNegative("bearing_stiffness[" + std::to_string(i) + "]", bearing_stiffness[i]);
  if (!mesh_) throw InvalidInput("dynamics: no mesh table");
  fallback_.relative_tolerance = 1e-8;
  fallback_.absolute_tolerance = 1e-15;
  fallback_.max_step = 1e-4;
  build();
}

void DynamicsEstimator::build() {
  // A refusal while building (a speed no excitation or propagator can take) names the settings a
  // user gives, not the derived ones (speed in rad/s, output interval) the parts below check.
  try {
    buildModel();
  } catch (const InvalidInput& e) {
    throw InvalidInput("dynamics.speed_rpm = " + formatValue(rig_.dynamics.speed_rpm) + " with output_rate = " +
                       formatValue(requested_rate_) + ": " + e.what());
  }
  ++rebuilds_;
}

void DynamicsEstimator::buildModel() {
  const DynamicsConfig& d = rig_.dynamics;
  const GearRotorParameters p = rigRotorParameters(rig_, *mesh_, bearing_stiffness_);
  RigExcitationSpec spec;
  spec.speed = d.speed_rpm * kTwoPi / 60.0;
  spec.te_amplitude = d.transmission_error_amplitude;
  spec.backlash = d.backlash;
  spec.balanced_load = true;
  spec.torque.kind = TorqueProfile::Kind::kLive;
  spec.torque.mean = d.torque;
  spec.torque.live = torque_;
  auto excitation = std::make_shared<RigExcitation>(mesh_, p, spec);
  auto model = std::make_shared<GearRotorModel>(p, excitation);
  const double period = 1.0 / excitation->meshFrequency();
  const double per_period = std::max(1.0, std::round(period * requested_rate_));
  const double interval = period / per_period;
  // A mesh so slow that its period overflows the grid arithmetic (0 or NaN samples) would make
  // every advanceTo() convert NaN to an index.
  if (!(interval > 0.0 && std::isfinite(interval))) throwInvalid("mesh period", period, "gives no usable output grid");
  std::unique_ptr<PeriodicExponentialPropagator> propagator;
  if (d.bearing_clearance[0] == 0.0 && d.bearing_clearance[1] == 0.0) {
    propagator = std::make_unique<PeriodicExponentialPropagator>(*model, 0.0, interval);
  }
  // Kept only now, all together: a refused rebuild leaves the last model, grid and propagators.
  propagator_ = std::move(propagator);  // first: the old one refers to the old model
  model_ = std::move(model);
  interval_ = interval;
}

void DynamicsEstimator::reset(double t, double torque) {
  requireFinite("t", t);
  requireFinite("torque", torque);
  origin_ = t;
  k_ = 0;
  *torque_ = torque;
  y_ = staticEquilibrium(*model_, 0.0);
  started_ = true;
}

void DynamicsEstimator::setTorque(double torque) {
  requireFinite("torque", torque);
  *torque_ = torque;
}

void DynamicsEstimator::setBearingStiffness(const std::array<double, 2>& k) {
  for (int i = 0; i < 2; ++i) {
    // The field name is built only on failure: this runs on every accepted input.
    if (!(k[i] >= 0.0)) requireNonNegative("bearing_stiffness[" + std::to_string(i) + "]", k[i]);
  }
  bool changed = false;
  for (int i = 0; i < 2; ++i) changed |= std::abs(k[i] - bearing_stiffness_[i]) > 0.01 * std::max(bearing_stiffness_[i], 1.0);
  if (!changed) return;
  bearing_stiffness_ = k;
  // Keep the state, the origin and the sample index: the rebuilt model's phase and output grid
  // both count from the same origin, so the mesh phase continues without a jump.
  build();
}

void DynamicsEstimator::setDamping(double mesh_damping_ratio, double bearing_damping_ratio) {
  requireNonNegative("mesh_damping_ratio", mesh_damping_ratio);
  requireNonNegative("bearing_damping_ratio", bearing_damping_ratio);
  rig_.dynamics.mesh_damping_ratio = mesh_damping_ratio;
  rig_.dynamics.bearing_damping_ratio = bearing_damping_ratio;
  build();  // keeps state, origin and sample index, as setBearingStiffness does
}

void DynamicsEstimator::setFidelity(Fidelity fidelity) { fidelity_ = fidelity; }

bool DynamicsEstimator::floquetMargin(double* margin) const {
  if (!propagator_) return false;
  const Eigen::Matrix<std::complex<double>, 6, 1> mu = Eigen::EigenSolver<Matrix6>(propagator_->monodromy(), false).eigenvalues();
  *margin = 1.0 - mu.cwiseAbs().maxCoeff();
  return true;
}

DynamicsSample DynamicsEstimator::sample(double t_rel, const State6& y) const {
  DynamicsSample s;
  s.t = origin_ + t_rel;
  s.state = y;
  s.dynamic_te = model_->forces(t_rel, y).delta;  // from the state: continuous
  // On a tooth switch the force, static TE and flank flags jump: report the right limit.
  MeshInstant m;
  const double t_eval = meshForSample(model_->excitation(), t_rel, interval_, m);
  const GearRotorForces f = model_->forces(t_eval, y);
  s.mesh_force = f.mesh;
  s.phase = m.phase < 1e-6 ? 0.0 : m.phase;  // the switch itself, not 1e-6 of an interval after it
  s.torque = *torque_;
  const double ks = m.k_drive + m.k_back;
  s.static_te = ks > 0.0 ? m.drive_force / ks : 0.0;
  s.drive_flank_loaded = f.regime.code[0] == 1;
  s.back_flank_loaded = f.regime.code[1] == 1;
  return s;
}

void DynamicsEstimator::advanceTo(double t, const std::function<void(const DynamicsSample&)>& sink) {
  requireFinite("t", t);
  if (!started_) throw InvalidInput("dynamics: advanceTo before reset");
  if (t < time() - 1e-12) {
    throw InvalidInput("t = " + formatValue(t) + ": before the current time " + formatValue(time()) + " (time went backwards; reset)");
  }
  const double samples = std::floor((t - origin_) / interval_ + 1e-9) - k_;
  if (samples > kMaxSamplesPerAdvance) {
    throw InvalidInput("t = " + formatValue(t) + ": a gap of " + formatValue(t - time()) + " s (" + formatValue(samples) +
                       " samples) is too long to integrate in one call; reset at the new time instead");
  }
  const long k_end = k_ + static_cast<long>(samples);
  const double torque = *torque_;
  if (fidelity_ != Fidelity::kFull && k_end > k_) {
    // Reduced fidelities run on the same grid; the observer's first call is the start state.
    const long k0 = k_;
    y_ = integrateReduced(*model_, fidelity_, k0 * interval_, y_, k_end * interval_, interval_,
                          [&](double t_rel, const State6& y) {
                            if (t_rel <= k0 * interval_) return;
                            ++k_;
                            if (sink) sink(sample(t_rel, y));
                          });
    k_ = k_end;
    return;
  }
  while (k_ < k_end) {
    const double t_k = k_ * interval_, t_next = (k_ + 1) * interval_;
    bool done = false;
    if (propagator_) {
      PeriodicExponentialPropagator::Augmented z = propagator_->augment(t_k, y_);
      if (propagator_->step(k_, z, torque, torque)) {
        y_ = z.head<6>();
        done = true;
      }
    }
    if (!done) {
      y_ = integrate(*model_, IntegratorMethod::kDopri5, fallback_, t_k, y_, t_next, interval_, nullptr);
      ++fallback_intervals_;
    }
    ++k_;
    if (sink) sink(sample(t_next, y_));
  }
}

}  // namespace drivetrain_stiffness

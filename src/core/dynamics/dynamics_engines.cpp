#include "drivetrain_stiffness/core/dynamics/dynamics_engines.hpp"

#include <cmath>
#include <complex>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/turns.hpp"

namespace drivetrain_stiffness {

void SlicedDynamics::build(std::shared_ptr<const SlicedMesh> mesh_slices,
                           const GearRotorParameters& p, const DynamicsConfig& d) {
  slices = std::move(mesh_slices);
  // The live node's load follows the input (RigExcitationSpec::balanced_load): F_d = T / r_p.
  model = std::make_unique<GearRotorModel>(
      p, std::make_shared<const SlicedExcitation>(slices, d.transmission_error_amplitude,
                                                  d.backlash, 1.0 / p.pinion_base_radius, 0.0));
  const bool clearance = p.bearing_clearance[0] > 0.0 || p.bearing_clearance[1] > 0.0;
  exact = clearance ? nullptr
                    : std::make_unique<SlicedModalPropagator>(
                          p, slices, d.transmission_error_amplitude, d.backlash);
}

void SlicedDynamics::setParameters(const GearRotorParameters& p) {
  model->setParameters(p);
  if (exact) exact->setParameters(p);
}

GearRotorParameters DynamicsModel::parameters() const {
  return rigRotorParameters(*rig, *mesh, bearing_stiffness, damping);
}

double DynamicsModel::nominalMeshFrequency() const {
  return rig->dynamics.speed_rpm / 60.0 * mesh->geometry().spec().teeth[0];
}

double DynamicsModel::driveForce(double torque) const {
  return torque / mesh->geometry().baseRadius(0);
}

const SlicedDynamics& DynamicsModel::moving(Fidelity fidelity) const {
  return fidelity == Fidelity::kLinearModal ? mean : full;
}

double DynamicsModel::slicesIn(double h, double f) const {
  return std::abs(f) * h * full.slices->size();
}

void DynamicsWorkspace::intervalMapsStale() {
  if (interval_maps) interval_maps->invalidate();
  maps_settle = MapsSettle::kNotAsked;
}

EngineResult PropagationEngine::interval(const DynamicsModel&, DynamicsWorkspace&) {
  return EngineResult::kDeclinedNoSuchOperation;
}

EngineResult PropagationEngine::propagate(const DynamicsModel&, DynamicsWorkspace&, double) {
  return EngineResult::kDeclinedNoSuchOperation;
}

EngineResult PeriodicEngine::interval(const DynamicsModel& m, DynamicsWorkspace& w) {
  // Near a knee a flank may lift and land again between two samples (contactsSettle): not here.
  const PeriodicExponentialPropagator* p = m.periodic.get();
  if (!p) return EngineResult::kDeclinedNoPropagator;
  const double t_k = w.k * m.interval;
  if (w.torque_changes == 0) {
    if (!p->contactsSettle(w.torque)) return EngineResult::kDeclinedContactsMayChange;
    PeriodicExponentialPropagator::Augmented z = p->augment(t_k, w.y);
    if (!p->step(w.k, z, w.torque, w.torque)) return EngineResult::kDeclinedLeftLinearRegime;
    w.y = z.head<6>();
    return EngineResult::kDone;
  }
  // The torque held at the sample, then each input from its stamp (the own-stamp rule): the held
  // torque's propagation plus each step's size times the response to a unit step at its instant.
  bool settles = p->contactsSettle(w.interval_torque);
  for (int i = 0; i < w.torque_changes && settles; ++i)
    settles = p->contactsSettle(w.torque_change[i].torque);
  if (!settles) return EngineResult::kDeclinedContactsMayChange;
  State6 added = State6::Zero();
  double before = w.interval_torque;
  for (int i = 0; i < w.torque_changes; ++i) {
    added += (w.torque_change[i].torque - before) *
             p->torqueStepResponse(w.k, w.torque_change[i].offset);
    before = w.torque_change[i].torque;
  }
  PeriodicExponentialPropagator::Augmented z = p->augment(t_k, w.y);
  if (!p->step(w.k, z, w.interval_torque, w.interval_torque, &added))
    return EngineResult::kDeclinedLeftLinearRegime;
  w.y = z.head<6>();
  return EngineResult::kDone;
}

EngineResult Dopri5Engine::interval(const DynamicsModel& m, DynamicsWorkspace& w) {
  const double t_k = w.k * m.interval, t_next = (w.k + 1) * m.interval;
  if (w.torque_changes == 0) {
    w.y = integrate(*m.nominal, IntegratorMethod::kDopri5, m.fallback, t_k, w.y, t_next, m.interval,
                    nullptr);
    ++w.fallback_intervals;
    return EngineResult::kDone;
  }
  // Piecewise between the stamps, each piece with the torque held before it.
  double from = t_k, held = w.interval_torque;
  for (int i = 0; i <= w.torque_changes; ++i) {
    const double to = i < w.torque_changes ? t_k + w.torque_change[i].offset : t_next;
    m.nominal->setTorqueInput(held);
    if (to > from)
      w.y = integrate(*m.nominal, IntegratorMethod::kDopri5, m.fallback, from, w.y, to, to - from,
                      nullptr);
    if (i < w.torque_changes) held = w.torque_change[i].torque;
    from = to;
  }
  m.nominal->setTorqueInput(w.torque);
  ++w.fallback_intervals;
  return EngineResult::kDone;
}

void Dopri5Engine::stretch(const DynamicsModel& m, DynamicsWorkspace& w, double t0, double t1,
                           State6& y, double& phase) {
  w.t_state = t0;  // the motion input's anchor
  GearRotorModel& model = *m.moving(w.fidelity).model;
  model.setMotionInput(MeshMotion{w.t_state, w.phase, w.mesh_frequency});
  model.setTorqueInput(w.torque);
  y = integrate(model, IntegratorMethod::kDopri5, m.fallback, t0, y, t1, t1 - t0, nullptr);
  phase += w.mesh_frequency * (t1 - t0);
  ++w.fallback_intervals;
}

EngineResult Dopri5Engine::propagate(const DynamicsModel& m, DynamicsWorkspace& w, double t_rel) {
  stretch(m, w, w.t_state, t_rel, w.y, w.phase);
  w.phase = wrapTurns(w.phase);
  w.t_state = t_rel;
  return EngineResult::kDone;
}

EngineResult SlicedModalEngine::propagate(const DynamicsModel& m, DynamicsWorkspace& w,
                                          double t_rel) {
  // full: the sliced model; linear_modal: the same with the period's mean stiffness (one slice).
  // Where the state is in no linear regime (both flanks unloaded at once: no mesh stiffness)
  // dopri5 on the same sliced model along the same motion takes over for a stretch.
  const SlicedModalPropagator& exact = *m.moving(w.fidelity).exact;
  const auto dopri5 = [&m, &w](double t0, double t1, State6& y, double& phase) {
    Dopri5Engine::stretch(m, w, t0, t1, y, phase);
  };
  propagateMeasured(exact, w.y, w.phase, w.mesh_frequency, w.t_state, t_rel, m.driveForce(w.torque),
                    dopri5);
  w.phase = wrapTurns(w.phase);
  w.t_state = t_rel;
  return EngineResult::kDone;
}

EngineResult QuasiStaticEngine::propagate(const DynamicsModel& m, DynamicsWorkspace& w,
                                          double t_rel) {
  // reduced_models.hpp, m_s -> 0: each shaft is a damped oscillator on its bearing pushed by
  // -/+ F_d, held over the step; the mesh deflection is the static one of the slice the phase is
  // in, in the flank state that force puts it in (AntiBacklashMesh::flankContact), so delta' = 0
  // inside a slice and the torsional coordinate follows from delta = x + x_p - x_g - e.
  const double h = t_rel - w.t_state, drive_force = m.driveForce(w.torque);
  State6& y = w.y;
  const GearRotorParameters& p = m.full.model->parameters();
  shaftStep(p.pinion_mass, p.bearing_damping[0], p.bearing_stiffness[0], -drive_force, h, y[0],
            y[3]);
  shaftStep(p.gear_mass, p.bearing_damping[1], p.bearing_stiffness[1], drive_force, h, y[1], y[4]);
  const double f = w.mesh_frequency;
  w.phase = wrapTurns(w.phase + f * h);
  // On the period's tooth switch (to 1e-7 of a period: where a sample lands on it) the slice the
  // motion enters, the right limit in time, as meshForSample reports the nominal model's.
  double look = w.phase;
  if (std::min(w.phase, 1.0 - w.phase) < 1e-7 && f != 0.0) {
    look = wrapTurns(w.phase + std::copysign(1e-6, f));
  }
  const SlicedMesh& slices = *m.full.slices;
  const int j = slices.sliceAt(look, f < 0.0);
  const double k1 = slices.k1(j), kc = slices.kChain(j), fp = slices.mesh().preloadForce();
  // AntiBacklashMesh::flankContact: both flanks delta = F / (k1 + k_c); the back path lifted
  // delta = (F - F_p) / k1; the drive flank lifted delta = (F + F_p) / k_c; an ordinary gear
  // F / k1 + b sign F.
  double delta = 0.0;
  if (slices.antiBacklash()) {
    switch (AntiBacklashMesh::flankContact(drive_force, k1, kc, fp)) {
      case FlankContact::kBoth: delta = drive_force / (k1 + kc); break;
      case FlankContact::kDriveOnly: delta = (drive_force - fp) / k1; break;
      case FlankContact::kBackOnly: delta = (drive_force + fp) / kc; break;
    }
  } else if (k1 > 0.0) {
    delta = drive_force / k1 + std::copysign(m.rig->dynamics.backlash, drive_force);
  }
  const double a = m.rig->dynamics.transmission_error_amplitude, theta = kTwoPi * w.phase;
  y[2] = delta - y[0] + y[1] + a * std::sin(theta);
  y[5] = -y[3] + y[4] + a * kTwoPi * f * std::cos(theta);
  w.t_state = t_rel;
  return EngineResult::kDone;
}

void QuasiStaticEngine::shaftStep(double m, double c, double k, double force, double h, double& x,
                                  double& v) {
  // m x'' + c x' + k x = F held: about the static deflection F / k, the free response of the damped
  // oscillator, u = e^{-sigma t} (u0 cos(w_d t) + (v0 + sigma u0) sin(w_d t) / w_d) and
  // v = e^{-sigma t} (v0 cos(w_d t) - (sigma v0 + (k/m) u0) sin(w_d t) / w_d), sigma = c / 2m,
  // w_d = sqrt(k/m - sigma^2) (substitute to check: u'' + 2 sigma u' + (k/m) u = 0, u(0) = u0,
  // u'(0) = v0). Over-damped, w_d is imaginary and the same expressions are real (cosh, sinh);
  // critically damped, sin(w_d t) / w_d -> t. Tested against the nominal quasi_static, whose shafts
  // go by Eigen's matrix exponential (test_dynamics_estimator.cpp).
  if (!(k > 0.0)) {  // no bearing stiffness: the shaft is free, F / m accelerates it
    x += v * h + 0.5 * force / m * h * h;
    v += force / m * h;
    return;
  }
  const double sigma = 0.5 * c / m, w2 = k / m;
  const std::complex<double> wd = std::sqrt(std::complex<double>(w2 - sigma * sigma, 0.0));
  const std::complex<double> cos_term = std::cos(wd * h);
  const std::complex<double> sinc =
      std::abs(wd * h) < 1e-8 ? std::complex<double>(h, 0.0) : std::sin(wd * h) / wd;
  const double decay = std::exp(-sigma * h), u0 = x - force / k, v0 = v;
  x = force / k + decay * (u0 * cos_term.real() + (v0 + sigma * u0) * sinc.real());
  v = decay * (v0 * cos_term.real() - (sigma * v0 + w2 * u0) * sinc.real());
}

EngineResult IntervalMapsEngine::mapsInterval(const DynamicsModel& m, DynamicsWorkspace& w,
                                              int& i) {
  // The same trust as the periodic propagators' at the nominal phase: a torque whose contacts
  // settle between samples (contactsSettle, tabulated with those propagators) and the loaded
  // regime checked at the stretch's ends; elsewhere the slices are crossed one by one, each with
  // its bound (propagateLinear).
  using Settle = DynamicsWorkspace::MapsSettle;
  if (!m.full.exact || !m.periodic) return EngineResult::kDeclinedNoPropagator;
  if (!m.periodic->contactsSettle(w.torque)) return EngineResult::kDeclinedContactsMayChange;
  const double f = m.nominalMeshFrequency();
  const double per_period = std::round(1.0 / (f * m.interval));
  if (!(f > 0.0) ||
      !(per_period >= 1.0 && per_period <= PeriodicExponentialPropagator::kMaxIntervalsPerPeriod))
    return EngineResult::kDeclinedGridNotPeriodic;
  if (!w.interval_maps || w.interval_maps->intervals() != static_cast<int>(per_period) ||
      w.interval_maps->meshFrequency() != f) {
    w.interval_maps =
        std::make_unique<SlicedIntervalMaps>(*m.full.slices, static_cast<int>(per_period), f);
    w.maps_settle = Settle::kNotAsked;
  }
  // The settling table holds for the parameters now while their swing gain is not larger
  // (docs/model.md "Back to one product per sample at the nominal speed").
  if (w.maps_settle == Settle::kNotAsked)
    w.maps_settle = m.full.exact->loadedSwingGain() <= 1.05 * m.periodic->settleGain()
                        ? Settle::kHolds
                        : Settle::kFails;
  if (w.maps_settle == Settle::kFails) return EngineResult::kDeclinedSwingGainTooLarge;
  i = static_cast<int>(w.k % w.interval_maps->intervals());
  return EngineResult::kDone;
}

EngineResult IntervalMapsEngine::interval(const DynamicsModel& m, DynamicsWorkspace& w) {
  int i = -1;
  const EngineResult found = mapsInterval(m, w, i);
  if (found != EngineResult::kDone) return found;
  const SlicedModalPropagator& exact = *m.full.exact;
  SlicedIntervalMaps& maps = *w.interval_maps;
  const int n = maps.intervals();
  const double f = maps.meshFrequency(), t0 = w.k * m.interval, t1 = (w.k + 1) * m.interval;
  const double drive_force = m.driveForce(w.torque);
  if (!exact.inLoadedRegime(w.y, w.phase, f)) return EngineResult::kDeclinedNotInLoadedRegime;
  // Before any work: the first use crosses.
  if (!maps.available(exact, i)) return EngineResult::kDeclinedMapsNotMade;
  State6 y = w.y;
  double phase = w.phase;
  int j = 0;
  const int end = maps.boundaries(i);
  const double u = f * (w.t_state - t0);  // [turns] from the interval's start
  if (u > 1e-9 * maps.offset(i, end)) {
    // Off the grid (an input's stamp): exactly to the next slice boundary, then its tail map, from
    // the loaded regime there (the exact part goes through any change of the contacts).
    j = maps.boundaryAtOrBefore(i, u) + 1;
    if (j > end) return EngineResult::kDeclinedPastLastBoundary;
    const double h = (maps.offset(i, j) - u) / f;
    if (h > 0.0 && !exact.propagate(y, phase, f, h, drive_force))
      return EngineResult::kDeclinedLeftLinearRegime;
    if (!exact.inLoadedRegime(y, static_cast<double>(i) / n + maps.offset(i, j), f))
      return EngineResult::kDeclinedNotInLoadedRegime;
  }
  if (!maps.toEnd(exact, i, j, y, drive_force)) return EngineResult::kDeclinedMapsUnusable;
  // The grid's own phase at the interval's end: the period's tooth switch is 0, the slice entered.
  phase = i + 1 == n ? 0.0 : static_cast<double>(i + 1) / n;
  if (!exact.inLoadedRegime(y, phase, f)) return EngineResult::kDeclinedNotInLoadedRegime;
  w.y = y;
  w.phase = phase;
  w.t_state = t1;
  ++w.mapped_stretches;
  return EngineResult::kDone;
}

EngineResult IntervalMapsEngine::propagate(const DynamicsModel& m, DynamicsWorkspace& w,
                                           double t_rel) {
  if (!(t_rel > w.t_state)) return EngineResult::kDeclinedNothingToPropagate;
  const double t0 = w.k * m.interval;
  // Off the grid: the slices one by one.
  if (std::abs(w.t_state - t0) > 1e-9 * m.interval) return EngineResult::kDeclinedOffGrid;
  int i = -1;
  const EngineResult found = mapsInterval(m, w, i);
  if (found != EngineResult::kDone) return found;
  const SlicedModalPropagator& exact = *m.full.exact;
  SlicedIntervalMaps& maps = *w.interval_maps;
  const double f = maps.meshFrequency(), u = f * (t_rel - t0);
  const int j = maps.boundaryAtOrBefore(i, u);
  // Inside the first slice: nothing to gain.
  if (j == 0 || j == maps.boundaries(i)) return EngineResult::kDeclinedWithinOneSlice;
  const double drive_force = m.driveForce(w.torque);
  if (!exact.inLoadedRegime(w.y, w.phase, f)) return EngineResult::kDeclinedNotInLoadedRegime;
  State6 y = w.y;
  if (!maps.fromStart(exact, i, j, y, drive_force)) return EngineResult::kDeclinedMapsUnusable;
  double phase = static_cast<double>(i) / maps.intervals() + maps.offset(i, j);
  if (!exact.inLoadedRegime(y, phase, f)) return EngineResult::kDeclinedNotInLoadedRegime;
  const double h = t_rel - (t0 + maps.offset(i, j) / f);
  if (h > 0.0 && !exact.propagate(y, phase, f, h, drive_force))
    return EngineResult::kDeclinedLeftLinearRegime;
  w.y = y;
  w.phase = wrapTurns(phase);
  w.t_state = t_rel;
  ++w.mapped_stretches;
  return EngineResult::kDone;
}

}  // namespace drivetrain_stiffness

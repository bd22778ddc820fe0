#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/dynamics/turns.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

/// Whether the engine left the step to the fallback: every reason does, kDone alone does not.
bool declined(EngineResult r) {
  switch (r) {
    case EngineResult::kDone: return false;
    case EngineResult::kDeclinedNoSuchOperation:
    case EngineResult::kDeclinedNoPropagator:
    case EngineResult::kDeclinedContactsMayChange:
    case EngineResult::kDeclinedLeftLinearRegime:
    case EngineResult::kDeclinedNotInLoadedRegime:
    case EngineResult::kDeclinedGridNotPeriodic:
    case EngineResult::kDeclinedSwingGainTooLarge:
    case EngineResult::kDeclinedMapsNotMade:
    case EngineResult::kDeclinedMapsUnusable:
    case EngineResult::kDeclinedOffGrid:
    case EngineResult::kDeclinedPastLastBoundary:
    case EngineResult::kDeclinedWithinOneSlice:
    case EngineResult::kDeclinedNothingToPropagate: return true;
  }
  return true;
}

}  // namespace

DynamicsEstimator::DynamicsEstimator(const RigConfig& rig,
                                     const std::array<double, 2>& bearing_stiffness,
                                     double output_rate)
    : DynamicsEstimator(std::make_shared<const RigConfig>(rig), bearing_stiffness, output_rate,
                        std::make_shared<const AntiBacklashMesh>(rig)) {}

DynamicsEstimator::DynamicsEstimator(std::shared_ptr<const RigConfig> rig,
                                     const std::array<double, 2>& bearing_stiffness,
                                     double output_rate,
                                     std::shared_ptr<const AntiBacklashMesh> mesh) {
  model_.rig = std::move(rig);
  model_.bearing_stiffness = bearing_stiffness;
  model_.requested_rate = output_rate;
  model_.mesh = std::move(mesh);
  if (!model_.rig)
    throw std::invalid_argument("DynamicsEstimator: no rig");  // a caller's bug, not bad data
  model_.damping = DampingRatios::of(model_.rig->dynamics);
  if (!model_.rig->dynamics.present)
    throw InvalidInput("dynamics: the gearbox file has no 'dynamics:' block");
  requirePositive("output_rate", output_rate);
  for (int i = 0; i < 2; ++i)
    requireNonNegative("bearing_stiffness[" + std::to_string(i) + "]", bearing_stiffness[i]);
  if (!model_.mesh) throw InvalidInput("dynamics: no mesh table");
  IntegratorOptions& fallback = model_.fallback;
  fallback.relative_tolerance = 1e-8;
  fallback.absolute_tolerance = 1e-15;
  fallback.max_step = 1e-4;
  // ~0.1 s of work per call at most: a 1 ms interval needs a few hundred steps even with its
  // contacts opening; only an advance over a long gap with the contacts open reaches this, and it
  // is refused (the caller restarts the dynamics) rather than stalling the input that asked for it.
  fallback.max_steps = 100000;
  build();
}

EngineChoice DynamicsEstimator::chooseEngines() {
  if (!ws_.following) {
    // The nominal phase, full fidelity (the reduced ones: advanceReduced). Where the periodic
    // propagators do not apply (the contacts may change in the interval), an anti-backlash mesh
    // without bearing clearance goes onto the sliced propagation, exact through every change of
    // the contacts; an ordinary gear's open backlash is no linear regime, so it takes dopri5.
    const DynamicsConfig& d = model_.rig->dynamics;
    const bool onto_sliced = ws_.fidelity == Fidelity::kFull && model_.mesh->antiBacklash() &&
                             d.bearing_clearance[0] == 0.0 && d.bearing_clearance[1] == 0.0;
    return {&periodic_, onto_sliced ? nullptr : &dopri5_};
  }
  // Along the sliced propagation: the interval maps first at the nominal phase (full fidelity, an
  // anti-backlash mesh, the periodic propagators' settling table), then slice by slice.
  EngineChoice c;
  if (!ws_.measured && ws_.fidelity == Fidelity::kFull && model_.full.exact && model_.periodic &&
      model_.full.slices->antiBacklash())
    c.first = &maps_;
  if (ws_.fidelity == Fidelity::kQuasiStatic)
    c.fallback = &quasi_static_;
  else if (model_.moving(ws_.fidelity).exact)
    c.fallback = &sliced_;
  else
    c.fallback = &dopri5_;  // bearing clearance
  return c;
}

void DynamicsEstimator::build() {
  // A refusal while building (a speed no excitation or propagator can take) names the settings a
  // user gives, not the derived ones (speed in rad/s, output interval) the parts below check.
  try {
    buildModel();
  } catch (const InvalidInput& e) {
    throw InvalidInput("dynamics.speed_rpm = " + formatValue(model_.rig->dynamics.speed_rpm) +
                       " with output_rate = " + formatValue(model_.requested_rate) + ": " +
                       e.what());
  }
  ++ws_.rebuilds;
}

void DynamicsEstimator::buildModel() {
  const DynamicsConfig& d = model_.rig->dynamics;
  const GearRotorParameters p = model_.parameters();
  RigExcitationSpec spec;
  spec.speed = d.speed_rpm * kTwoPi / 60.0;
  spec.te_amplitude = d.transmission_error_amplitude;
  spec.backlash = d.backlash;
  spec.balanced_load = true;
  spec.torque.kind = TorqueProfile::Kind::kInput;  // the measured torque, given to the model below
  spec.torque.mean = d.torque;
  auto excitation = std::make_shared<RigExcitation>(model_.mesh, p, spec);
  auto model = std::make_unique<GearRotorModel>(p, excitation);
  model->setTorqueInput(ws_.torque);
  const double period = 1.0 / excitation->meshFrequency();
  const double per_period = std::max(1.0, std::round(period * model_.requested_rate));
  const double interval = period / per_period;
  // A mesh so slow that its period overflows the grid arithmetic (0 or NaN samples) would make
  // every advanceTo() convert NaN to an index.
  if (!(interval > 0.0 && std::isfinite(interval)))
    throwInvalid("mesh period", period, "gives no usable output grid");
  std::unique_ptr<PeriodicExponentialPropagator> propagator;
  if (d.bearing_clearance[0] == 0.0 && d.bearing_clearance[1] == 0.0) {
    // With the settling bound: near a knee advanceTo moves onto the sliced propagation.
    propagator = std::make_unique<PeriodicExponentialPropagator>(*model, 0.0, interval, 1.0, true);
  }
  // Kept only now, all together: a refused rebuild leaves the last model, grid and propagators.
  model_.periodic = std::move(propagator);
  model_.nominal = std::move(model);
  model_.interval = interval;
}

void DynamicsEstimator::reset(double t, double torque) {
  requireFinite("t", t);
  requireFinite("torque", torque);
  if (model_.periodic_stale) {
    build();  // parameters changed while following the motion: the nominal phase needs its own
              // propagators
    model_.periodic_stale = false;
  }
  ws_.following = false;
  ws_.measured = false;
  // The periodic propagators (and their settling table) may be new.
  ws_.maps_settle = DynamicsWorkspace::MapsSettle::kNotAsked;
  ws_.t_state = 0.0;
  ws_.origin = t;
  ws_.k = 0;
  ws_.torque = torque;
  ws_.interval_torque = torque;
  ws_.torque_changes = 0;
  model_.nominal->setTorqueInput(torque);
  ws_.y = staticEquilibrium(*model_.nominal, 0.0);
  ws_.started = true;
}

void DynamicsEstimator::setTorque(double torque, std::optional<double> at) {
  requireFinite("torque", torque);
  if (at) requireFinite("at", *at);
  if (ws_.started && !ws_.following && at) {
    // Nominal phase: the state sits on sample k; a torque stamped inside the interval that
    // follows takes effect at its stamp (advanceTo applies it there), not at the sample.
    // A stamp on the sample to rounding (1e-9 of an interval: a picosecond at 1 kHz) is taken
    // there.
    const double interval = model_.interval;
    const double offset = (*at - ws_.origin) - ws_.k * interval;
    if (offset > 1e-9 * interval && offset < interval) {
      if (ws_.torque_changes == 0) ws_.interval_torque = ws_.torque;
      if (ws_.torque_changes < kMaxTorqueChangesPerInterval) {
        ws_.torque_change[ws_.torque_changes++] = {offset, torque};
      } else {
        // More than kMaxTorqueChangesPerInterval inputs inside one output interval: the last
        // one's torque is replaced (its stamp kept), so no storage grows on the input path.
        ws_.torque_change[kMaxTorqueChangesPerInterval - 1].torque = torque;
      }
    }
  }
  ws_.torque = torque;
  model_.nominal->setTorqueInput(torque);
}

void DynamicsEstimator::setBearingStiffness(const std::array<double, 2>& k,
                                            std::optional<double> at) {
  for (int i = 0; i < 2; ++i) {
    // The field name is built only on failure: this runs on every accepted input.
    if (!(k[i] >= 0.0)) requireNonNegative("bearing_stiffness[" + std::to_string(i) + "]", k[i]);
  }
  std::array<double, 2>& now = model_.bearing_stiffness;
  bool changed = false;
  for (int i = 0; i < 2; ++i) changed |= std::abs(k[i] - now[i]) > 0.01 * std::max(now[i], 1.0);
  if (!changed) return;
  if (ws_.started && at) moveTo(*at);
  const std::array<double, 2> before = now;
  now = {bearingGridValue(k[0]), bearingGridValue(k[1])};
  try {
    parametersChanged();
  } catch (...) {
    now = before;  // refused: the last model stays
    throw;
  }
}

double DynamicsEstimator::bearingGridValue(double k) {
  // Grid points 1.01^n, n = round(ln k / ln 1.01): the nearest in ratio, within a factor 1.005 of
  // k. The same k, or any k between the same two midpoints, gives the same value to the bit (one
  // exp of an integer times a constant), which is what lets the sliced propagation recognise a
  // value met before (SlicedModalPropagator::kKeptParameterSets). With the 1 % dead band of
  // setBearingStiffness, the stiffness the model runs with stays within 1 % of the estimator's.
  if (!(k >= 1.0) || !std::isfinite(k)) return k;
  static const double kStep = std::log(1.01);
  return std::exp(std::round(std::log(k) / kStep) * kStep);
}

void DynamicsEstimator::setDamping(double mesh_damping_ratio, double bearing_damping_ratio) {
  requireDampingRatio("mesh_damping_ratio", mesh_damping_ratio);
  requireDampingRatio("bearing_damping_ratio", bearing_damping_ratio);
  const DampingRatios before = model_.damping;
  model_.damping = {mesh_damping_ratio, bearing_damping_ratio};
  try {
    parametersChanged();
  } catch (...) {
    model_.damping = before;  // refused: the last model stays
    throw;
  }
}

void DynamicsEstimator::parametersChanged() {
  // Running: keep the state, the origin and the sample index, and go on with the speed-independent
  // propagation (its slices are decomposed lazily as they are crossed) instead of rebuilding the
  // periodic propagators inside the caller. Not started: rebuild those for the next reset.
  if (!ws_.started) {
    build();
    return;
  }
  ws_.intervalMapsStale();
  if (ws_.following) {
    const GearRotorParameters p = model_.parameters();
    model_.full.setParameters(p);
    model_.mean.setParameters(p);
  } else {
    startFollowing();  // with the parameters as they are now
  }
  model_.periodic_stale = true;
  ++ws_.rebuilds;
}

void DynamicsEstimator::setMotionSlices(int slices) {
  if (slices < 4 || slices > 65536)
    throwInvalid("motion_slices", slices, "must be in [4, 65536] per mesh period");
  if (slices == model_.motion_slices) return;
  if (ws_.following)
    throw InvalidInput(
        "motion_slices: cannot change while following the measured motion (reset first)");
  model_.motion_slices = slices;
  model_.full = SlicedDynamics{};
  model_.mean = SlicedDynamics{};
  ws_.interval_maps.reset();
}

void DynamicsEstimator::startFollowing() {
  const GearRotorParameters p = model_.parameters();
  if (!model_.full.model) {
    const DynamicsConfig& d = model_.rig->dynamics;
    model_.full.build(std::make_shared<const SlicedMesh>(model_.mesh, model_.motion_slices), p, d);
    // linear_modal along the measured motion: the same model with the period's mean stiffness.
    model_.mean.build(SlicedMesh::periodMean(model_.mesh), p, d);
  } else {
    model_.full.setParameters(p);
    model_.mean.setParameters(p);
  }
  // The parameters may have changed while stopped (parametersChanged rebuilds only the periodic
  // propagators then): the interval maps are made again for these.
  ws_.intervalMapsStale();
  // The state sits on grid sample k; the nominal phase there (RigExcitation: turns = f t).
  ws_.t_state = ws_.k * model_.interval;
  ws_.mesh_frequency = model_.nominalMeshFrequency();
  ws_.phase = wrapTurns(ws_.mesh_frequency * ws_.t_state);
  ws_.following = true;
  // Torque inputs already taken inside the interval that follows: each from its own stamp. The
  // torque held after them is the newest one given (setTorque without a stamp may have come last).
  if (ws_.torque_changes > 0) {
    const double start = ws_.t_state, newest = ws_.torque;
    ws_.torque = ws_.interval_torque;
    for (int i = 0; i < ws_.torque_changes; ++i) {
      propagateTo(start + ws_.torque_change[i].offset);
      ws_.torque = ws_.torque_change[i].torque;
    }
    ws_.torque = newest;
    ws_.torque_changes = 0;
  }
}

void DynamicsEstimator::moveTo(double t) {
  requireFinite("t", t);
  if (!ws_.started) throw InvalidInput("dynamics: not started (reset first)");
  if (!ws_.following) startFollowing();
  const double t_rel = t - ws_.origin;
  if (t_rel < ws_.t_state - 1e-12) {
    throw InvalidInput("t = " + formatValue(t) + ": before the current time " +
                       formatValue(time()) + " (time went backwards; reset)");
  }
  if (std::floor(t_rel / model_.interval + 1e-9) > ws_.k) {
    throw InvalidInput("t = " + formatValue(t) +
                       ": output samples lie before it; advanceTo(t) first");
  }
  propagateTo(t_rel);
}

void DynamicsEstimator::followMotion(double t, double mesh_phase, double mesh_frequency) {
  requireFinite("mesh_phase", mesh_phase);
  requireFinite("mesh_frequency", mesh_frequency);
  moveTo(t);
  ws_.measured = true;
  ws_.phase = wrapTurns(mesh_phase);
  ws_.mesh_frequency = mesh_frequency;
}

double DynamicsEstimator::meshPhase() const {
  return ws_.following ? ws_.phase : model_.nominalMeshFrequency() * ws_.k * model_.interval;
}

double DynamicsEstimator::meshFrequency() const {
  return ws_.following ? ws_.mesh_frequency : model_.nominalMeshFrequency();
}

void DynamicsEstimator::requireSliceBound(double t_rel) const {
  const double h = t_rel - ws_.t_state, crossings = model_.slicesIn(h, ws_.mesh_frequency);
  if (crossings > kMaxSlicesPerAdvance) {
    throw InvalidInput("t = " + formatValue(ws_.origin + t_rel) + ": " + formatValue(h) +
                       " s at a mesh frequency of " + formatValue(ws_.mesh_frequency) +
                       " Hz crosses " + formatValue(crossings) + " phase slices (more than " +
                       formatValue(kMaxSlicesPerAdvance) +
                       " in one call); reset at the new time instead");
  }
}

void DynamicsEstimator::countSlicesCrossed(double t_rel, double& crossed) const {
  crossed += model_.slicesIn(model_.interval, ws_.mesh_frequency);
  if (crossed > kMaxSlicesPerAdvance) {
    throw InvalidInput(
        "t = " + formatValue(ws_.origin + t_rel) +
        ": at the nominal phase, where the interval maps do not " +
        "apply, this advance crossed more than " + formatValue(kMaxSlicesPerAdvance) +
        " phase slices one by one (a mesh frequency of " + formatValue(ws_.mesh_frequency) +
        " Hz); the dynamics up to " + formatValue(ws_.origin + ws_.t_state) +
        " s are kept, reset at the new time for the rest");
  }
}

void DynamicsEstimator::propagateTo(double t_rel) {
  if (!(t_rel - ws_.t_state > 0.0)) return;
  requireSliceBound(t_rel);
  chooseEngines().fallback->propagate(model_, ws_, t_rel);
}

void DynamicsEstimator::followFromHere(double t_rel, const Sink& sink) {
  startFollowing();
  advanceFollowing(t_rel, sink);
}

void DynamicsEstimator::advanceFollowing(double t_rel, const Sink& sink) {
  // Along the encoders every interval crosses its slices one by one: the whole advance is bounded
  // before any work. At the nominal phase an interval the maps take costs one product whatever the
  // speed, so only the intervals crossed slice by slice count against the bound, as they come: a
  // gap the periodic propagators took before the move (up to ~max_gap) is taken again where the
  // maps apply, and elsewhere the work stays bounded (the samples before the refusal are kept).
  if (ws_.measured) requireSliceBound(t_rel);
  double crossed = 0.0;
  const double interval = model_.interval;
  const long k_end = static_cast<long>(std::floor(t_rel / interval + 1e-9));
  while (ws_.k < k_end) {
    const EngineChoice c = chooseEngines();
    if (!c.first || declined(c.first->interval(model_, ws_))) {
      if (!ws_.measured) countSlicesCrossed((ws_.k + 1) * interval, crossed);
      propagateTo((ws_.k + 1) * interval);
    }
    ++ws_.k;
    if (sink) sink(movingSample());
  }
  const EngineChoice c = chooseEngines();
  if (!c.first || declined(c.first->propagate(model_, ws_, t_rel))) propagateTo(t_rel);
}

DynamicsWork DynamicsEstimator::work() const {
  DynamicsWork w;
  w.rebuilds = ws_.rebuilds;
  w.fallback_intervals = ws_.fallback_intervals;
  w.mapped_stretches = ws_.mapped_stretches;
  w.interval_maps_made = ws_.interval_maps ? ws_.interval_maps->intervalsMade() : 0L;
  w.exact = ws_.following ? model_.full.exact != nullptr : model_.periodic != nullptr;
  if (const SlicedModalPropagator* s = model_.moving(ws_.fidelity).exact.get()) {
    w.sliced = true;
    w.slices_crossed = s->slicesCrossed();
    w.decompositions = s->decompositions();
    w.general_decompositions = s->generalDecompositions();
    w.regime_changes = s->regimeChanges();
    w.checked_substeps = s->checkedSubsteps();
    w.kept_sets_reused = s->keptSetsReused();
  }
  return w;
}

bool DynamicsEstimator::floquetMargin(double* margin) const {
  Matrix6 monodromy;
  if (ws_.following) {
    // The sliced model at the measured speed, as if it were held (standing: no period), in the
    // contact regime the state is in now: above the anti-backlash knee the back path is lifted and
    // the drive flank alone sets the stiffness, so the both-flank period map would describe a
    // motion that is not happening. In no linear regime (a flank opening), no margin.
    const SlicedModalPropagator* exact = model_.full.exact.get();
    if (!exact || ws_.mesh_frequency == 0.0) return false;
    const std::optional<Matrix6> m = exact->monodromy(ws_.mesh_frequency, ws_.y, ws_.phase);
    if (!m) return false;
    monodromy = *m;
  } else {
    if (!model_.periodic) return false;
    monodromy = model_.periodic->monodromy();
  }
  const Eigen::Matrix<std::complex<double>, 6, 1> mu =
      Eigen::EigenSolver<Matrix6>(monodromy, false).eigenvalues();
  *margin = 1.0 - mu.cwiseAbs().maxCoeff();
  return true;
}

DynamicsSample DynamicsEstimator::sample(double t_rel, const State6& y) const {
  return sampleOf(*model_.nominal, t_rel, y);
}

DynamicsSample DynamicsEstimator::movingSample() {
  // The model over the sliced mesh the fidelity runs, its motion and torque inputs the state's.
  GearRotorModel& model = *model_.moving(ws_.fidelity).model;
  model.setMotionInput(MeshMotion{ws_.t_state, ws_.phase, ws_.mesh_frequency});
  model.setTorqueInput(ws_.torque);
  return sampleOf(model, ws_.t_state, ws_.y);
}

DynamicsSample DynamicsEstimator::sampleOf(const GearRotorModel& model, double t_rel,
                                           const State6& y) const {
  DynamicsSample s;
  s.t = ws_.origin + t_rel;
  s.state = y;
  s.dynamic_te = model.forces(t_rel, y).delta;  // from the state: continuous
  // On a tooth switch the force, static TE and flank flags jump: report the right limit.
  MeshInstant m;
  const double right_limit = meshForSample(model, t_rel, model_.interval, m);
  const GearRotorForces f = model.forces(right_limit, y);
  s.mesh_force = f.mesh;
  // The switch itself (a sample lands on it to rounding, either side, where meshForSample looked
  // past it), not 1e-6 of a period after it: a phase a few ulps above the switch looks 1e-6 plus
  // those ulps ahead, which the test of the looked-at phase against 1e-6 alone would let through.
  s.phase = right_limit != t_rel || m.phase < 1e-6 || 1.0 - m.phase < 1e-6 ? 0.0 : m.phase;
  s.torque = ws_.torque;
  const double ks = m.k_drive + m.k_back;
  s.static_te = ks > 0.0 ? m.drive_force / ks : 0.0;
  s.drive_flank_loaded = f.regime.code[0] == 1;
  s.back_flank_loaded = f.regime.code[1] == 1;
  return s;
}

void DynamicsEstimator::advanceTo(double t, const Sink& sink) {
  requireFinite("t", t);
  if (!ws_.started) throw InvalidInput("dynamics: advanceTo before reset");
  if (t < time() - 1e-12) {
    throw InvalidInput("t = " + formatValue(t) + ": before the current time " +
                       formatValue(time()) + " (time went backwards; reset)");
  }
  const double samples = std::floor((t - ws_.origin) / model_.interval + 1e-9) - ws_.k;
  if (samples > kMaxSamplesPerAdvance) {
    throw InvalidInput(
        "t = " + formatValue(t) + ": a gap of " + formatValue(t - time()) + " s (" +
        formatValue(samples) +
        " samples) is too long to integrate in one call; reset at the new time instead");
  }
  if (ws_.following) {
    advanceFollowing(t - ws_.origin, sink);
    return;
  }
  const long k_end = ws_.k + static_cast<long>(samples);
  if (ws_.fidelity != Fidelity::kFull) {
    advanceReduced(k_end, sink);
  } else {
    advanceNominal(t, k_end, sink);
  }
}

void DynamicsEstimator::advanceReduced(long k_end, const Sink& sink) {
  if (!(k_end > ws_.k)) return;
  ws_.torque_changes = 0;  // reduced fidelities hold each torque from the sample before it
  // On the same grid; the observer's first call is the start state.
  const long k0 = ws_.k;
  const double interval = model_.interval;
  ws_.y = integrateReduced(*model_.nominal, ws_.fidelity, k0 * interval, ws_.y, k_end * interval,
                           interval, [&](double t_rel, const State6& y) {
                             if (t_rel <= k0 * interval) return;
                             ++ws_.k;
                             if (sink) sink(sample(t_rel, y));
                           });
  ws_.k = k_end;
}

void DynamicsEstimator::advanceNominal(double t, long k_end, const Sink& sink) {
  // Each interval by the periodic propagators with its torque inputs at their stamps; where the
  // contacts may change in it, dopri5 or onto the sliced propagation at the nominal phase (which
  // takes the inputs at their stamps, as after a parameter change).
  while (ws_.k < k_end) {
    const double t_next = (ws_.k + 1) * model_.interval;
    const EngineChoice c = chooseEngines();
    if (declined(c.first->interval(model_, ws_))) {
      if (!c.fallback) {
        followFromHere(t - ws_.origin, sink);
        return;
      }
      c.fallback->interval(model_, ws_);
    }
    ++ws_.k;
    ws_.torque_changes = 0;
    if (sink) sink(sample(t_next, ws_.y));
  }
}

}  // namespace drivetrain_stiffness

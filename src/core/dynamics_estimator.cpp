#include "drivetrain_stiffness/core/dynamics_estimator.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/turns.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

DynamicsEstimator::DynamicsEstimator(const RigConfig& rig,
                                     const std::array<double, 2>& bearing_stiffness,
                                     double output_rate)
    : DynamicsEstimator(std::make_shared<const RigConfig>(rig), bearing_stiffness, output_rate,
                        std::make_shared<const AntiBacklashMesh>(rig)) {}

DynamicsEstimator::DynamicsEstimator(std::shared_ptr<const RigConfig> rig,
                                     const std::array<double, 2>& bearing_stiffness,
                                     double output_rate,
                                     std::shared_ptr<const AntiBacklashMesh> mesh)
    : rig_(std::move(rig)),
      bearing_stiffness_(bearing_stiffness),
      requested_rate_(output_rate),
      mesh_(std::move(mesh)) {
  if (!rig_)
    throw std::invalid_argument("DynamicsEstimator: no rig");  // a caller's bug, not bad data
  damping_ = DampingRatios::of(rig_->dynamics);
  if (!rig_->dynamics.present)
    throw InvalidInput("dynamics: the gearbox file has no 'dynamics:' block");
  requirePositive("output_rate", output_rate);
  for (int i = 0; i < 2; ++i)
    requireNonNegative("bearing_stiffness[" + std::to_string(i) + "]", bearing_stiffness[i]);
  if (!mesh_) throw InvalidInput("dynamics: no mesh table");
  fallback_.relative_tolerance = 1e-8;
  fallback_.absolute_tolerance = 1e-15;
  fallback_.max_step = 1e-4;
  // ~0.1 s of work per call at most: a 1 ms interval needs a few hundred steps even with its
  // contacts opening; only an advance over a long gap with the contacts open reaches this, and it
  // is refused (the caller restarts the dynamics) rather than stalling the input that asked for it.
  fallback_.max_steps = 100000;
  build();
}

void DynamicsEstimator::build() {
  // A refusal while building (a speed no excitation or propagator can take) names the settings a
  // user gives, not the derived ones (speed in rad/s, output interval) the parts below check.
  try {
    buildModel();
  } catch (const InvalidInput& e) {
    throw InvalidInput("dynamics.speed_rpm = " + formatValue(rig_->dynamics.speed_rpm) +
                       " with output_rate = " + formatValue(requested_rate_) + ": " + e.what());
  }
  ++rebuilds_;
}

void DynamicsEstimator::buildModel() {
  const DynamicsConfig& d = rig_->dynamics;
  const GearRotorParameters p = currentParameters();
  RigExcitationSpec spec;
  spec.speed = d.speed_rpm * kTwoPi / 60.0;
  spec.te_amplitude = d.transmission_error_amplitude;
  spec.backlash = d.backlash;
  spec.balanced_load = true;
  spec.torque.kind = TorqueProfile::Kind::kInput;  // the measured torque, given to the model below
  spec.torque.mean = d.torque;
  auto excitation = std::make_shared<RigExcitation>(mesh_, p, spec);
  auto model = std::make_unique<GearRotorModel>(p, excitation);
  model->setTorqueInput(torque_);
  const double period = 1.0 / excitation->meshFrequency();
  const double per_period = std::max(1.0, std::round(period * requested_rate_));
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
  propagator_ = std::move(propagator);
  model_ = std::move(model);
  interval_ = interval;
}

void DynamicsEstimator::reset(double t, double torque) {
  requireFinite("t", t);
  requireFinite("torque", torque);
  if (periodic_stale_) {
    build();  // parameters changed while following the motion: the nominal phase needs its own
              // propagators
    periodic_stale_ = false;
  }
  following_ = false;
  measured_ = false;
  maps_settle_ = -1;  // the periodic propagators (and their settling table) may be new
  t_state_ = 0.0;
  origin_ = t;
  k_ = 0;
  torque_ = torque;
  interval_torque_ = torque;
  torque_changes_ = 0;
  model_->setTorqueInput(torque);
  y_ = staticEquilibrium(*model_, 0.0);
  started_ = true;
}

void DynamicsEstimator::setTorque(double torque, std::optional<double> at) {
  requireFinite("torque", torque);
  if (at) requireFinite("at", *at);
  if (started_ && !following_ && at) {
    // Nominal phase: the state sits on sample k_; a torque stamped inside the interval that
    // follows takes effect at its stamp (advanceTo applies it there), not at the sample.
    // A stamp on the sample to rounding (1e-9 of an interval: a picosecond at 1 kHz) is taken
    // there.
    const double offset = (*at - origin_) - k_ * interval_;
    if (offset > 1e-9 * interval_ && offset < interval_) {
      if (torque_changes_ == 0) interval_torque_ = torque_;
      if (torque_changes_ < kMaxTorqueChangesPerInterval) {
        torque_change_[torque_changes_++] = {offset, torque};
      } else {
        // More than kMaxTorqueChangesPerInterval inputs inside one output interval: the last
        // one's torque is replaced (its stamp kept), so no storage grows on the input path.
        torque_change_[kMaxTorqueChangesPerInterval - 1].torque = torque;
      }
    }
  }
  torque_ = torque;
  model_->setTorqueInput(torque);
}

void DynamicsEstimator::setBearingStiffness(const std::array<double, 2>& k,
                                            std::optional<double> at) {
  for (int i = 0; i < 2; ++i) {
    // The field name is built only on failure: this runs on every accepted input.
    if (!(k[i] >= 0.0)) requireNonNegative("bearing_stiffness[" + std::to_string(i) + "]", k[i]);
  }
  bool changed = false;
  for (int i = 0; i < 2; ++i)
    changed |= std::abs(k[i] - bearing_stiffness_[i]) > 0.01 * std::max(bearing_stiffness_[i], 1.0);
  if (!changed) return;
  if (started_ && at) moveTo(*at);
  const std::array<double, 2> before = bearing_stiffness_;
  bearing_stiffness_ = {bearingGridValue(k[0]), bearingGridValue(k[1])};
  try {
    parametersChanged();
  } catch (...) {
    bearing_stiffness_ = before;  // refused: the last model stays
    throw;
  }
}

double DynamicsEstimator::bearingGridValue(double k) {
  // Grid points 1.01^n, n = round(ln k / ln 1.01): the nearest in ratio, within a factor 1.005 of
  // k. The same k, or any k between the same two midpoints, gives the same bits (one exp of an
  // integer times a constant), which is what lets the sliced propagation recognise a value met
  // before. With the 1 % dead band above, the stiffness the model runs with stays within 1 % of
  // the estimator's, as it did when a change took the estimator's value itself.
  if (!(k >= 1.0) || !std::isfinite(k)) return k;
  static const double kStep = std::log(1.01);
  return std::exp(std::round(std::log(k) / kStep) * kStep);
}

void DynamicsEstimator::setDamping(double mesh_damping_ratio, double bearing_damping_ratio) {
  requireDampingRatio("mesh_damping_ratio", mesh_damping_ratio);
  requireDampingRatio("bearing_damping_ratio", bearing_damping_ratio);
  const DampingRatios before = damping_;
  damping_ = {mesh_damping_ratio, bearing_damping_ratio};
  try {
    parametersChanged();
  } catch (...) {
    damping_ = before;  // refused: the last model stays
    throw;
  }
}

void DynamicsEstimator::parametersChanged() {
  // Running: keep the state, the origin and the sample index, and go on with the speed-independent
  // propagation (its slices are decomposed lazily as they are crossed) instead of rebuilding the
  // periodic propagators inside the caller. Not started: rebuild those for the next reset.
  if (!started_) {
    build();
    return;
  }
  intervalMapsStale();
  if (following_) {
    const GearRotorParameters p = currentParameters();
    full_.setParameters(p);
    mean_.setParameters(p);
  } else {
    startFollowing();  // with the parameters as they are now
  }
  periodic_stale_ = true;
  ++rebuilds_;
}

GearRotorParameters DynamicsEstimator::currentParameters() const {
  return rigRotorParameters(*rig_, *mesh_, bearing_stiffness_, damping_);
}

double DynamicsEstimator::driveForce() const { return torque_ / mesh_->geometry().baseRadius(0); }

void DynamicsEstimator::intervalMapsStale() {
  if (interval_maps_) interval_maps_->invalidate();
  maps_settle_ = -1;
}

double DynamicsEstimator::nominalMeshFrequency() const {
  return rig_->dynamics.speed_rpm / 60.0 * mesh_->geometry().spec().teeth[0];
}

void DynamicsEstimator::setMotionSlices(int slices) {
  if (slices < 4 || slices > 65536)
    throwInvalid("motion_slices", slices, "must be in [4, 65536] per mesh period");
  if (slices == motion_slices_) return;
  if (following_)
    throw InvalidInput(
        "motion_slices: cannot change while following the measured motion (reset first)");
  motion_slices_ = slices;
  full_ = SlicedDynamics{};
  mean_ = SlicedDynamics{};
  interval_maps_.reset();
}

void DynamicsEstimator::SlicedDynamics::build(std::shared_ptr<const SlicedMesh> mesh_slices,
                                              const GearRotorParameters& p,
                                              const DynamicsConfig& d) {
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

void DynamicsEstimator::SlicedDynamics::setParameters(const GearRotorParameters& p) {
  model->setParameters(p);
  if (exact) exact->setParameters(p);
}

void DynamicsEstimator::startFollowing() {
  const GearRotorParameters p = currentParameters();
  if (!full_.model) {
    full_.build(std::make_shared<const SlicedMesh>(mesh_, motion_slices_), p, rig_->dynamics);
    // linear_modal along the measured motion: the same model with the period's mean stiffness.
    mean_.build(SlicedMesh::periodMean(mesh_), p, rig_->dynamics);
  } else {
    full_.setParameters(p);
    mean_.setParameters(p);
  }
  // The parameters may have changed while stopped (parametersChanged rebuilds only the periodic
  // propagators then): the interval maps are made again for these.
  intervalMapsStale();
  // The state sits on grid sample k_; the nominal phase there (RigExcitation: turns = f t).
  t_state_ = k_ * interval_;
  mesh_frequency_ = nominalMeshFrequency();
  phase_ = wrapTurns(mesh_frequency_ * t_state_);
  following_ = true;
  // Torque inputs already taken inside the interval that follows: each from its own stamp. The
  // torque held after them is the newest one given (setTorque without a stamp may have come last).
  if (torque_changes_ > 0) {
    const double start = t_state_, newest = torque_;
    torque_ = interval_torque_;
    for (int i = 0; i < torque_changes_; ++i) {
      propagateTo(start + torque_change_[i].offset);
      torque_ = torque_change_[i].torque;
    }
    torque_ = newest;
    torque_changes_ = 0;
  }
}

void DynamicsEstimator::moveTo(double t) {
  requireFinite("t", t);
  if (!started_) throw InvalidInput("dynamics: not started (reset first)");
  if (!following_) startFollowing();
  const double t_rel = t - origin_;
  if (t_rel < t_state_ - 1e-12) {
    throw InvalidInput("t = " + formatValue(t) + ": before the current time " +
                       formatValue(time()) + " (time went backwards; reset)");
  }
  if (std::floor(t_rel / interval_ + 1e-9) > k_) {
    throw InvalidInput("t = " + formatValue(t) +
                       ": output samples lie before it; advanceTo(t) first");
  }
  propagateTo(t_rel);
}

void DynamicsEstimator::followMotion(double t, double mesh_phase, double mesh_frequency) {
  requireFinite("mesh_phase", mesh_phase);
  requireFinite("mesh_frequency", mesh_frequency);
  moveTo(t);
  measured_ = true;
  phase_ = wrapTurns(mesh_phase);
  mesh_frequency_ = mesh_frequency;
}

double DynamicsEstimator::meshPhase() const {
  return following_ ? phase_ : nominalMeshFrequency() * k_ * interval_;
}

double DynamicsEstimator::meshFrequency() const {
  return following_ ? mesh_frequency_ : nominalMeshFrequency();
}

double DynamicsEstimator::slicesIn(double h) const {
  return std::abs(mesh_frequency_) * h * full_.slices->size();
}

void DynamicsEstimator::requireSliceBound(double t_rel) const {
  const double h = t_rel - t_state_, crossings = slicesIn(h);
  if (crossings > kMaxSlicesPerAdvance) {
    throw InvalidInput("t = " + formatValue(origin_ + t_rel) + ": " + formatValue(h) +
                       " s at a mesh frequency of " + formatValue(mesh_frequency_) +
                       " Hz crosses " + formatValue(crossings) + " phase slices (more than " +
                       formatValue(kMaxSlicesPerAdvance) +
                       " in one call); reset at the new time instead");
  }
}

void DynamicsEstimator::countSlicesCrossed(double t_rel, double& crossed) const {
  crossed += slicesIn(interval_);
  if (crossed > kMaxSlicesPerAdvance) {
    throw InvalidInput(
        "t = " + formatValue(origin_ + t_rel) +
        ": at the nominal phase, where the interval maps do not " +
        "apply, this advance crossed more than " + formatValue(kMaxSlicesPerAdvance) +
        " phase slices one by one (a mesh frequency of " + formatValue(mesh_frequency_) +
        " Hz); the dynamics up to " + formatValue(origin_ + t_state_) +
        " s are kept, reset at the new time for the rest");
  }
}

void DynamicsEstimator::propagateTo(double t_rel) {
  const double h = t_rel - t_state_;
  if (!(h > 0.0)) return;
  requireSliceBound(t_rel);
  const double drive_force = driveForce();
  if (fidelity_ == Fidelity::kQuasiStatic) {
    propagateQuasiStatic(h, drive_force);
    t_state_ = t_rel;
    return;
  }
  // full: the sliced model; linear_modal: the same with the period's mean stiffness (one slice).
  // Exact through every change of the contacts between linear regimes (located on the exact
  // solution; a flank lifting, landing or its damper clipping are each such a change); where the
  // state is in none (both flanks unloaded at once: no mesh stiffness) dopri5 on the same sliced
  // model along the same motion takes over for a stretch (propagateMeasured). With bearing
  // clearance, dopri5 alone.
  const SlicedModalPropagator* exact = moving().exact.get();
  const auto dopri5 = [this](double t0, double t1, State6& y, double& phase) {
    t_state_ = t0;  // the motion input's anchor (movingModelAtState)
    y = integrate(movingModelAtState(), IntegratorMethod::kDopri5, fallback_, t0, y, t1, t1 - t0,
                  nullptr);
    phase += mesh_frequency_ * (t1 - t0);
    ++fallback_intervals_;
  };
  if (exact) {
    propagateMeasured(*exact, y_, phase_, mesh_frequency_, t_state_, t_rel, drive_force, dopri5);
  } else {
    dopri5(t_state_, t_rel, y_, phase_);
  }
  phase_ = wrapTurns(phase_);
  t_state_ = t_rel;
}

void DynamicsEstimator::followFromHere(double t_rel,
                                       const std::function<void(const DynamicsSample&)>& sink) {
  startFollowing();
  advanceFollowing(t_rel, sink);
}

void DynamicsEstimator::advanceFollowing(double t_rel,
                                         const std::function<void(const DynamicsSample&)>& sink) {
  // Along the encoders every interval crosses its slices one by one: the whole advance is bounded
  // before any work. At the nominal phase an interval the maps take costs one product whatever the
  // speed, so only the intervals crossed slice by slice count against the bound, as they come: a
  // gap the periodic propagators took before the move (up to ~max_gap) is taken again where the
  // maps apply, and elsewhere the work stays bounded (the samples before the refusal are kept).
  if (measured_) requireSliceBound(t_rel);
  double crossed = 0.0;
  const long k_end = static_cast<long>(std::floor(t_rel / interval_ + 1e-9));
  while (k_ < k_end) {
    if (!intervalByMaps()) {
      if (!measured_) countSlicesCrossed((k_ + 1) * interval_, crossed);
      propagateTo((k_ + 1) * interval_);
    }
    ++k_;
    if (sink) sink(movingSample());
  }
  if (!headByMaps(t_rel)) propagateTo(t_rel);
}

int DynamicsEstimator::mapsInterval() {
  // The same trust as the periodic propagators' at the nominal phase: a torque whose contacts
  // settle between samples (contactsSettle, tabulated with those propagators) and the loaded
  // regime checked at the stretch's ends; elsewhere the slices are crossed one by one, each with
  // its bound (propagateLinear).
  if (!following_ || measured_ || fidelity_ != Fidelity::kFull || !full_.exact || !propagator_ ||
      !full_.slices->antiBacklash() || !propagator_->contactsSettle(torque_)) {
    return -1;
  }
  const double f = nominalMeshFrequency();
  const double per_period = std::round(1.0 / (f * interval_));
  if (!(f > 0.0) ||
      !(per_period >= 1.0 && per_period <= PeriodicExponentialPropagator::kMaxIntervalsPerPeriod))
    return -1;
  if (!interval_maps_ || interval_maps_->intervals() != static_cast<int>(per_period) ||
      interval_maps_->meshFrequency() != f) {
    interval_maps_ =
        std::make_unique<SlicedIntervalMaps>(*full_.slices, static_cast<int>(per_period), f);
    maps_settle_ = -1;
  }
  // The settling table was made with the parameters of the last build; its answers hold for the
  // parameters now while their swing gain is not larger (the rule compares each margin with 1.5
  // gain J). The gain now comes from the slices' modes at the table's 16 phases: each slice holds
  // the table's mean over 1/256 of a period where the table read its value at the phase, so 5 % is
  // allowed for that, inside the rule's 1.5. Parameters whose modes let the mesh swing further (a
  // larger gain) leave the maps unused: every slice is then crossed with its own regime bound. (The
  // gain bounds the free swing without its decay, so the damping moves it little: a tenth of the
  // mesh damping stayed within the 5 % on the seed servo.)
  if (maps_settle_ < 0)
    maps_settle_ = full_.exact->loadedSwingGain() <= 1.05 * propagator_->settleGain() ? 1 : 0;
  if (maps_settle_ == 0) return -1;
  return static_cast<int>(k_ % interval_maps_->intervals());
}

bool DynamicsEstimator::intervalByMaps() {
  const int i = mapsInterval();
  if (i < 0) return false;
  const SlicedModalPropagator& exact = *full_.exact;
  const int n = interval_maps_->intervals();
  const double f = interval_maps_->meshFrequency(), t0 = k_ * interval_, t1 = (k_ + 1) * interval_;
  const double drive_force = driveForce();
  if (!exact.inLoadedRegime(y_, phase_, f)) return false;
  if (!interval_maps_->available(exact, i)) return false;  // before any work: the first use crosses
  State6 y = y_;
  double phase = phase_;
  int m = 0;
  const int end = interval_maps_->boundaries(i);
  const double u = f * (t_state_ - t0);  // [turns] from the interval's start
  if (u > 1e-9 * interval_maps_->offset(i, end)) {
    // Off the grid (an input's stamp): exactly to the next slice boundary, then its tail map, from
    // the loaded regime there (the exact part goes through any change of the contacts).
    m = interval_maps_->boundaryAtOrBefore(i, u) + 1;
    if (m > end) return false;
    const double h = (interval_maps_->offset(i, m) - u) / f;
    if (h > 0.0 && !exact.propagate(y, phase, f, h, drive_force)) return false;
    if (!exact.inLoadedRegime(y, static_cast<double>(i) / n + interval_maps_->offset(i, m), f))
      return false;
  }
  if (!interval_maps_->toEnd(exact, i, m, y, drive_force)) return false;
  // The grid's own phase at the interval's end: the period's tooth switch is 0, the slice entered.
  phase = i + 1 == n ? 0.0 : static_cast<double>(i + 1) / n;
  if (!exact.inLoadedRegime(y, phase, f)) return false;
  y_ = y;
  phase_ = phase;
  t_state_ = t1;
  ++mapped_stretches_;
  return true;
}

bool DynamicsEstimator::headByMaps(double t_rel) {
  if (!(t_rel > t_state_)) return false;
  const double t0 = k_ * interval_;
  if (std::abs(t_state_ - t0) > 1e-9 * interval_)
    return false;  // off the grid: the slices one by one
  const int i = mapsInterval();
  if (i < 0) return false;
  const SlicedModalPropagator& exact = *full_.exact;
  const double f = interval_maps_->meshFrequency(), u = f * (t_rel - t0);
  const int m = interval_maps_->boundaryAtOrBefore(i, u);
  if (m == 0 || m == interval_maps_->boundaries(i))
    return false;  // inside the first slice: nothing to gain
  const double drive_force = driveForce();
  if (!exact.inLoadedRegime(y_, phase_, f)) return false;
  State6 y = y_;
  if (!interval_maps_->fromStart(exact, i, m, y, drive_force)) return false;
  double phase =
      static_cast<double>(i) / interval_maps_->intervals() + interval_maps_->offset(i, m);
  if (!exact.inLoadedRegime(y, phase, f)) return false;
  const double h = t_rel - (t0 + interval_maps_->offset(i, m) / f);
  if (h > 0.0 && !exact.propagate(y, phase, f, h, drive_force)) return false;
  y_ = y;
  phase_ = wrapTurns(phase);
  t_state_ = t_rel;
  ++mapped_stretches_;
  return true;
}

void DynamicsEstimator::setFidelity(Fidelity fidelity) { fidelity_ = fidelity; }

bool DynamicsEstimator::floquetMargin(double* margin) const {
  Matrix6 monodromy;
  if (following_) {
    // The sliced model at the measured speed, as if it were held (standing: no period), in the
    // contact regime the state is in now: above the anti-backlash knee the back path is lifted and
    // the drive flank alone sets the stiffness, so the both-flank period map would describe a
    // motion that is not happening. In no linear regime (a flank opening), no margin.
    if (!full_.exact || mesh_frequency_ == 0.0) return false;
    const std::optional<Matrix6> m = full_.exact->monodromy(mesh_frequency_, y_, phase_);
    if (!m) return false;
    monodromy = *m;
  } else {
    if (!propagator_) return false;
    monodromy = propagator_->monodromy();
  }
  const Eigen::Matrix<std::complex<double>, 6, 1> mu =
      Eigen::EigenSolver<Matrix6>(monodromy, false).eigenvalues();
  *margin = 1.0 - mu.cwiseAbs().maxCoeff();
  return true;
}

DynamicsSample DynamicsEstimator::sample(double t_rel, const State6& y) const {
  return sampleOf(*model_, t_rel, y);
}

GearRotorModel& DynamicsEstimator::movingModelAtState() {
  GearRotorModel& model = *moving().model;
  model.setMotionInput(MeshMotion{t_state_, phase_, mesh_frequency_});
  model.setTorqueInput(torque_);
  return model;
}

DynamicsSample DynamicsEstimator::movingSample() {
  return sampleOf(movingModelAtState(), t_state_, y_);
}

void DynamicsEstimator::propagateQuasiStatic(double h, double drive_force) {
  // quasi_static along the measured motion (reduced_models.hpp: m_s -> 0): each shaft is a damped
  // oscillator on its bearing pushed by -/+ F_d, held over the step, so it is propagated exactly;
  // the mesh deflection is the static one of the slice the phase is in, in the flank state that
  // force puts it in (AntiBacklashMesh::flankContact: both flanks delta = F / (k1 + k_c); the back
  // path lifted delta = (F - F_p) / k1; the drive flank lifted delta = (F + F_p) / k_c; an ordinary
  // gear F / k1 + b sign F), so delta' = 0 inside a slice and the torsional coordinate follows
  // from delta = x + x_p - x_g - e.
  const GearRotorParameters& p = full_.model->parameters();
  shaftStep(p.pinion_mass, p.bearing_damping[0], p.bearing_stiffness[0], -drive_force, h, y_[0],
            y_[3]);
  shaftStep(p.gear_mass, p.bearing_damping[1], p.bearing_stiffness[1], drive_force, h, y_[1],
            y_[4]);
  phase_ = wrapTurns(phase_ + mesh_frequency_ * h);
  // On the period's tooth switch (to 1e-7 of a period: where a sample lands on it) the slice the
  // motion enters, the right limit in time, as meshForSample reports the nominal model's.
  double look = phase_;
  if (std::min(phase_, 1.0 - phase_) < 1e-7 && mesh_frequency_ != 0.0) {
    look = wrapTurns(phase_ + std::copysign(1e-6, mesh_frequency_));
  }
  const SlicedMesh& slices = *full_.slices;
  const int j = slices.sliceAt(look, mesh_frequency_ < 0.0);
  const double k1 = slices.k1(j), kc = slices.kChain(j), fp = slices.mesh().preloadForce();
  double delta = 0.0;
  if (slices.antiBacklash()) {
    switch (AntiBacklashMesh::flankContact(drive_force, k1, kc, fp)) {
      case FlankContact::kBoth: delta = drive_force / (k1 + kc); break;
      case FlankContact::kDriveOnly: delta = (drive_force - fp) / k1; break;
      case FlankContact::kBackOnly: delta = (drive_force + fp) / kc; break;
    }
  } else if (k1 > 0.0) {
    delta = drive_force / k1 + std::copysign(rig_->dynamics.backlash, drive_force);
  }
  const double a = rig_->dynamics.transmission_error_amplitude, theta = kTwoPi * phase_;
  y_[2] = delta - y_[0] + y_[1] + a * std::sin(theta);
  y_[5] = -y_[3] + y_[4] + a * kTwoPi * mesh_frequency_ * std::cos(theta);
}

void DynamicsEstimator::shaftStep(double m, double c, double k, double force, double h, double& x,
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

DynamicsSample DynamicsEstimator::sampleOf(const GearRotorModel& model, double t_rel,
                                           const State6& y) const {
  DynamicsSample s;
  s.t = origin_ + t_rel;
  s.state = y;
  s.dynamic_te = model.forces(t_rel, y).delta;  // from the state: continuous
  // On a tooth switch the force, static TE and flank flags jump: report the right limit.
  MeshInstant m;
  const double right_limit = meshForSample(model, t_rel, interval_, m);
  const GearRotorForces f = model.forces(right_limit, y);
  s.mesh_force = f.mesh;
  // The switch itself (a sample lands on it to rounding, either side, where meshForSample looked
  // past it), not 1e-6 of a period after it: a phase a few ulps above the switch looks 1e-6 plus
  // those ulps ahead, which the test of the looked-at phase against 1e-6 alone let through.
  s.phase = right_limit != t_rel || m.phase < 1e-6 || 1.0 - m.phase < 1e-6 ? 0.0 : m.phase;
  s.torque = torque_;
  const double ks = m.k_drive + m.k_back;
  s.static_te = ks > 0.0 ? m.drive_force / ks : 0.0;
  s.drive_flank_loaded = f.regime.code[0] == 1;
  s.back_flank_loaded = f.regime.code[1] == 1;
  return s;
}

bool DynamicsEstimator::slicedInsteadOfDopri5() const {
  // Full fidelity, an anti-backlash mesh, no bearing clearance: the sliced propagation is exact
  // through every change of the contacts (located on the exact solution), where dopri5 on the
  // phase table at rtol 1e-8 ran near real time (3.4x at 3 N m under torque_ripple's ripple,
  // 1.6x at -0.5 N m). An ordinary gear's open backlash is no linear regime
  // (dopri5 either way) and its interval maps do not exist: it stays on the periodic propagators
  // with dopri5 for the interval, which costs it nothing after the backlash closes.
  return fidelity_ == Fidelity::kFull && mesh_->antiBacklash() &&
         rig_->dynamics.bearing_clearance[0] == 0.0 && rig_->dynamics.bearing_clearance[1] == 0.0;
}

bool DynamicsEstimator::advanceIntervalWithTorqueChanges() {
  // The interval from sample k_ with the torque held at its start, then each input from its stamp
  // (the own-stamp rule). Exact: the held torque's propagation plus each step's size times the
  // response to a unit step at its instant (PeriodicExponentialPropagator::torqueStepResponse);
  // where the contacts may leave the linear regime, false (nothing done: the caller moves onto the
  // sliced propagation, which takes the inputs at their stamps), or with bearing clearance dopri5
  // piecewise between the stamps.
  const double t_k = k_ * interval_, t_next = (k_ + 1) * interval_;
  bool done = false;
  bool settles = propagator_ && propagator_->contactsSettle(interval_torque_);
  for (int i = 0; i < torque_changes_ && settles; ++i)
    settles = propagator_->contactsSettle(torque_change_[i].torque);
  if (settles) {
    State6 added = State6::Zero();
    double before = interval_torque_;
    for (int i = 0; i < torque_changes_; ++i) {
      added += (torque_change_[i].torque - before) *
               propagator_->torqueStepResponse(k_, torque_change_[i].offset);
      before = torque_change_[i].torque;
    }
    PeriodicExponentialPropagator::Augmented z = propagator_->augment(t_k, y_);
    if (propagator_->step(k_, z, interval_torque_, interval_torque_, &added)) {
      y_ = z.head<6>();
      done = true;
    }
  }
  if (!done && slicedInsteadOfDopri5()) return false;
  if (!done) {
    double from = t_k, held = interval_torque_;
    for (int i = 0; i <= torque_changes_; ++i) {
      const double to = i < torque_changes_ ? t_k + torque_change_[i].offset : t_next;
      model_->setTorqueInput(held);
      if (to > from)
        y_ = integrate(*model_, IntegratorMethod::kDopri5, fallback_, from, y_, to, to - from,
                       nullptr);
      if (i < torque_changes_) held = torque_change_[i].torque;
      from = to;
    }
    model_->setTorqueInput(torque_);
    ++fallback_intervals_;
  }
  ++k_;
  torque_changes_ = 0;
  return true;
}

void DynamicsEstimator::advanceTo(double t,
                                  const std::function<void(const DynamicsSample&)>& sink) {
  requireFinite("t", t);
  if (!started_) throw InvalidInput("dynamics: advanceTo before reset");
  if (t < time() - 1e-12) {
    throw InvalidInput("t = " + formatValue(t) + ": before the current time " +
                       formatValue(time()) + " (time went backwards; reset)");
  }
  const double samples = std::floor((t - origin_) / interval_ + 1e-9) - k_;
  if (samples > kMaxSamplesPerAdvance) {
    throw InvalidInput(
        "t = " + formatValue(t) + ": a gap of " + formatValue(t - time()) + " s (" +
        formatValue(samples) +
        " samples) is too long to integrate in one call; reset at the new time instead");
  }
  if (following_) {
    advanceFollowing(t - origin_, sink);
    return;
  }
  const long k_end = k_ + static_cast<long>(samples);
  const double torque = torque_;
  const bool settles = propagator_ && propagator_->contactsSettle(torque);
  if (k_end > k_ && torque_changes_ > 0 && fidelity_ == Fidelity::kFull) {
    if (!advanceIntervalWithTorqueChanges()) {
      // The contacts may change inside the interval: onto the sliced propagation at the nominal
      // phase (the torque inputs taken at their stamps there), as after a parameter change.
      followFromHere(t - origin_, sink);
      return;
    }
    if (sink) sink(sample(k_ * interval_, y_));
  }
  if (k_end > k_)
    torque_changes_ = 0;  // reduced fidelities hold each torque from the sample before it
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
    // Near a knee a flank may lift and land again between two samples (contactsSettle): not here.
    if (settles) {
      PeriodicExponentialPropagator::Augmented z = propagator_->augment(t_k, y_);
      if (propagator_->step(k_, z, torque, torque)) {
        y_ = z.head<6>();
        done = true;
      }
    }
    if (!done && slicedInsteadOfDopri5()) {
      // Near a knee, or a flank lifted: onto the sliced propagation at the nominal phase, which
      // locates every change of the contacts on the exact solution (until the next reset; where
      // the contacts settle again, one interval map per sample: SlicedIntervalMaps).
      followFromHere(t - origin_, sink);
      return;
    }
    if (!done) {
      y_ = integrate(*model_, IntegratorMethod::kDopri5, fallback_, t_k, y_, t_next, interval_,
                     nullptr);
      ++fallback_intervals_;
    }
    ++k_;
    if (sink) sink(sample(t_next, y_));
  }
}

}  // namespace drivetrain_stiffness

#include "drivetrain_stiffness/core/dynamics/reduced_models.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/MatrixFunctions>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/enum_names.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

const RigExcitation& rigExcitation(const GearRotorModel& model, const char* what) {
  const RigExcitation* e = model.rigExcitation();
  if (!e) throw InvalidInput(std::string("fidelity ") + what + ": needs a rig excitation");
  return *e;
}

long gridCount(double t0, double t_end, double interval) {
  requirePositive("output_interval", interval);
  const double n = (t_end - t0) / interval;
  if (!(n >= 0.0) || std::abs(n - std::round(n)) > 1e-6 * std::max(1.0, n)) {
    throwInvalid("t_end", t_end, "must be t0 plus a whole number of output intervals");
  }
  return std::lround(n);
}

// The excitation's k_drive + k_back is the table's k1 + k_c (k1 alone without a scissor spring):
// its period mean is meanMeshStiffness, the one mean of the library.
double meanStiffness(const RigExcitation& e) { return meanMeshStiffness(e.mesh()); }

// One shaft on its bearing, m x'' + c x' + k x = f(t), f linear over the interval (first-order
// hold): exact propagation through the exponential of
// [[0,1,0,0],[-k/m,-c/m,1/m,0],[0,0,0,1],[0,0,0,0]].
struct ShaftPropagator {
  Eigen::Matrix4d phi;
  ShaftPropagator(double m, double c, double k, double h) {
    Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
    a(0, 1) = 1.0;
    a(1, 0) = -k / m;
    a(1, 1) = -c / m;
    a(1, 2) = 1.0 / m;
    a(2, 3) = 1.0;
    // Balance displacement (um) against force (N): the exponential is accurate normwise.
    const Eigen::Vector4d s(1e-6, 1e-6 * std::sqrt(std::max(k, 1.0) / m), 1.0, 1.0 / h);
    phi = s.asDiagonal() * (s.cwiseInverse().asDiagonal() * (a * h) * s.asDiagonal()).exp() *
          s.cwiseInverse().asDiagonal();
  }
  void step(double& x, double& v, double f0, double f1, double h) const {
    Eigen::Vector4d z(x, v, f0, (f1 - f0) / h);
    z = phi * z;
    x = z[0];
    v = z[1];
  }
};

}  // namespace

namespace {
constexpr EnumName<Fidelity> kFidelities[] = {{Fidelity::kFull, "full"},
                                              {Fidelity::kQuasiStatic, "quasi_static"},
                                              {Fidelity::kLinearModal, "linear_modal"}};
}  // namespace

Fidelity parseFidelity(const std::string& field, const std::string& text) {
  return parseEnum(kFidelities, field, text);
}
const char* toString(Fidelity f) { return enumName(kFidelities, f); }

namespace {

// quasi_static on the grid (m_s -> 0): the shafts on their bearings under the drive force with a
// first-order hold, the mesh in static deflection at each sample.
State6 integrateQuasiStatic(const GearRotorModel& model, double t0, State6 y, long n,
                            double interval, const Observer& observe) {
  const GearRotorParameters& p = model.parameters();
  rigExcitation(model, "quasi_static");
  const ShaftPropagator pin(p.pinion_mass, p.bearing_damping[0], p.bearing_stiffness[0], interval);
  const ShaftPropagator gear(p.gear_mass, p.bearing_damping[1], p.bearing_stiffness[1], interval);
  MeshInstant m;
  model.meshAt(t0, m);
  double f = m.drive_force;
  for (long k = 0; k < n; ++k) {
    const double t = t0 + (k + 1) * interval;
    meshForSample(model, t, interval, m);  // on a tooth switch: the right limit
    pin.step(y[0], y[3], -f, -m.drive_force,
             interval);  // the pinion is pushed back by the mesh force
    gear.step(y[1], y[4], f, m.drive_force, interval);
    f = m.drive_force;
    const double ks = m.k_drive + m.k_back;
    const bool ordinary = m.k_back == 0.0 && m.preload_force == 0.0;
    const double delta =
        ks > 0.0 ? m.drive_force / ks + (ordinary ? std::copysign(m.backlash, m.drive_force) : 0.0)
                 : 0.0;
    const double x_new = delta - y[0] + y[1] + m.te;
    y[5] = (x_new - y[2]) /
           interval;  // torsional rate from the samples (the mode itself is not modelled)
    y[2] = x_new;
    if (observe) observe(t, y);
  }
  return y;
}

// linear_modal's propagator over one output interval [s]: the state [x_p x_g x v_p v_g v sin cos
// 1 u u'] as in the exponential method, the stiffness at its mean, balanced before exponentiating.
Eigen::Matrix<double, 11, 11> linearModalPropagator(const GearRotorModel& model,
                                                    const RigExcitation& e, const MeshInstant& m0,
                                                    double mean_force, double interval) {
  const GearRotorParameters& p = model.parameters();
  const double ks = meanStiffness(e), cs = p.mesh_damping, ms = model.equivalentMass();
  const double a_te = e.spec().te_amplitude, w = kTwoPi * e.meshFrequency();
  const double gain = e.torqueGain();
  Eigen::Matrix<double, 11, 11> a = Eigen::Matrix<double, 11, 11>::Zero();
  Eigen::Matrix<double, 1, 11> f = Eigen::Matrix<double, 1, 11>::Zero();
  // An ordinary gear closes its backlash b on the loaded flank: F = k_s (delta - b sign F).
  const bool ordinary = m0.k_back == 0.0 && m0.preload_force == 0.0;
  const double offset = ordinary ? std::copysign(m0.backlash, m0.drive_force) : 0.0;
  f << ks, -ks, ks, cs, -cs, cs, -ks * a_te, -cs * a_te * w, -ks * offset, 0, 0;
  a(0, 3) = a(1, 4) = a(2, 5) = 1.0;
  a.row(3) = -f / p.pinion_mass;
  a(3, 0) -= p.bearing_stiffness[0] / p.pinion_mass;
  a(3, 3) -= p.bearing_damping[0] / p.pinion_mass;
  a.row(4) = f / p.gear_mass;
  a(4, 1) -= p.bearing_stiffness[1] / p.gear_mass;
  a(4, 4) -= p.bearing_damping[1] / p.gear_mass;
  a.row(5) = -f / ms;
  a(5, 8) += mean_force / ms;
  a(5, 9) += gain / ms;
  a(6, 7) = w;
  a(7, 6) = -w;
  a(9, 10) = 1.0;
  const double w_max =
      std::sqrt(std::max({(ks + p.bearing_stiffness[0]) / p.pinion_mass,
                          (ks + p.bearing_stiffness[1]) / p.gear_mass, 2.0 * ks / ms}));
  Eigen::Matrix<double, 11, 1> s;
  s << 1e-6, 1e-6, 1e-6, 1e-6 * w_max, 1e-6 * w_max, 1e-6 * w_max, 1, 1, 1, 1, 1.0 / interval;
  return s.asDiagonal() * (s.cwiseInverse().asDiagonal() * (a * interval) * s.asDiagonal()).exp() *
         s.cwiseInverse().asDiagonal();
}

// linear_modal on the grid: one product with linearModalPropagator per output interval.
State6 integrateLinearModal(const GearRotorModel& model, double t0, const State6& y, long n,
                            double interval, const Observer& observe) {
  const RigExcitation& e = rigExcitation(model, "linear_modal");
  const double w = kTwoPi * e.meshFrequency(), psi = kTwoPi * e.spec().initial_phase;
  const TorqueProfile& torque = e.spec().torque;
  // The pinion torque at each sample: the model's input if it takes one (held), else the
  // profile's.
  const bool held = e.takesTorqueInput();
  const double input = model.torqueInput();
  auto torqueAt = [&](double t) { return held ? input : torque.at(t); };
  MeshInstant m0;
  model.meshAt(t0, m0);
  const double mean_force = m0.drive_force - e.torqueGain() * (torqueAt(t0) - torque.mean);
  const Eigen::Matrix<double, 11, 11> phi =
      linearModalPropagator(model, e, m0, mean_force, interval);
  Eigen::Matrix<double, 11, 1> z;
  z.head<6>() = y;
  z[6] = std::sin(w * t0 + psi);
  z[7] = std::cos(w * t0 + psi);
  z[8] = 1.0;
  double u = torqueAt(t0) - torque.mean;
  for (long k = 0; k < n; ++k) {
    const double t = t0 + (k + 1) * interval;
    const double u_next = torqueAt(t) - torque.mean;
    z[9] = u;
    z[10] = (u_next - u) / interval;
    z = phi * z;
    u = u_next;
    if (observe) observe(t, z.head<6>());
  }
  return z.head<6>();
}

}  // namespace

State6 integrateReduced(const GearRotorModel& model, Fidelity fidelity, double t0, const State6& y0,
                        double t_end, double interval, const Observer& observe) {
  const long n = gridCount(t0, t_end, interval);
  if (!y0.allFinite()) throw InvalidInput("initial state: contains a non-finite value");
  if (observe) observe(t0, y0);
  if (fidelity == Fidelity::kQuasiStatic)
    return integrateQuasiStatic(model, t0, y0, n, interval, observe);
  if (fidelity == Fidelity::kLinearModal)
    return integrateLinearModal(model, t0, y0, n, interval, observe);
  throw InvalidInput("integrateReduced: use integrate() for the full model");
}

IntegratorOptions autoOptions(IntegratorMethod method, double relative_tolerance,
                              const IntegratorScale& scale) {
  // dopri5 at the chosen rtol (in SI the absolute tolerance 1e-6 of it, in metres), every method
  // with steps of at most 0.1 ms (SI), and the divergence limit of the model's units.
  IntegratorOptions o;
  o.max_step = scale.max_step;
  o.divergence_limit = scale.divergence_limit;
  if (method == IntegratorMethod::kDopri5) {
    o.relative_tolerance = relative_tolerance;
    o.absolute_tolerance = relative_tolerance * scale.displacement;
  }
  return o;
}

double defaultPilotDuration(double run_duration, double output_interval) {
  return std::min(0.25 * run_duration, 40.0 * output_interval);
}

namespace {

// The pilot's span: the model from (t0, y0) to t_end on the output grid [s].
struct Pilot {
  const GearRotorModel& model;
  double t0;
  const State6& y0;
  double t_end, interval;
};

// delta at every output sample of `run` (which integrates with the observer it is given).
template <typename Run>
std::vector<double> deltas(const GearRotorModel& model, Run run) {
  std::vector<double> d;
  run([&](double t, const State6& y) { d.push_back(model.forces(t, y).delta); });
  return d;
}

double rmsError(const std::vector<double>& d, const std::vector<double>& ref) {
  double e = 0.0, r = 0.0;
  for (std::size_t i = 0; i < ref.size() && i < d.size(); ++i) {
    e += (d[i] - ref[i]) * (d[i] - ref[i]);
    r += ref[i] * ref[i];
  }
  return d.size() == ref.size() && r > 0.0 ? std::sqrt(e / r) : INFINITY;
}

bool accept(AutoChoice& choice, const std::string& name, double err, double error_bound) {
  choice.pilot_errors.emplace_back(name, err);
  return err <= 0.5 * error_bound;
}

// The exponential propagation's pilot, where the model can be linear and its set-up is predicted
// cheaper than dopri5's work over the run (both in dopri5 steps, from counts, not clocks: the same
// inputs always give the same choice). Set-up: one Magnus step (an 11x11 exponential, about
// kMagnusStepCost dopri5 steps) per 1/omega_max over a mesh period; then one 9x11 product per
// output sample. Built once, for the pilot and the run (choice.exponential). Returns the pilot's
// deltas (none where not built); `closed`: its contacts stayed closed through the pilot.
std::vector<double> exponentialPilot(const Pilot& pilot, double run_duration, long dopri_steps,
                                     double count_duration, AutoChoice& choice, bool& closed) {
  const double run = run_duration > 0.0 ? run_duration : std::numeric_limits<double>::infinity();
  const double dopri_cost = static_cast<double>(std::max(1L, dopri_steps)) * (run / count_duration);
  std::vector<double> exponential;
  try {
    const double exponential_cost = PeriodicExponentialPropagator::estimatedSetupSteps(
                                        pilot.model, *pilot.model.rigExcitation(), pilot.t0) *
                                        kMagnusStepCost +
                                    (std::isfinite(run) ? run / pilot.interval : 0.0);
    if (exponential_cost < dopri_cost) {
      auto propagator = std::make_shared<const PeriodicExponentialPropagator>(pilot.model, pilot.t0,
                                                                              pilot.interval);
      IntegrationStats stats;
      exponential = deltas(pilot.model, [&](const Observer& o) {
        propagator->run(pilot.y0, pilot.t_end, o, IntegratorOptions{}, &stats);
      });
      closed = stats.fallbacks == 0;
      choice.exponential = std::move(propagator);
    }
  } catch (const InvalidInput&) {
    choice.pilot_errors.emplace_back("exponential (not applicable)", INFINITY);
  }
  return exponential;
}

// The first reduced fidelity whose pilot meets the bound against `reference`, recorded in choice.
bool chooseReduced(const Pilot& pilot, const std::vector<double>& reference,
                   const std::string& reference_name, double error_bound, AutoChoice& choice) {
  for (Fidelity f : {Fidelity::kQuasiStatic, Fidelity::kLinearModal}) {
    const double err = rmsError(deltas(pilot.model,
                                       [&](const Observer& o) {
                                         integrateReduced(pilot.model, f, pilot.t0, pilot.y0,
                                                          pilot.t_end, pilot.interval, o);
                                       }),
                                reference);
    if (accept(choice, toString(f), err, error_bound)) {
      choice.fidelity = f;
      choice.exponential.reset();
      choice.reason = std::string(toString(f)) + " meets the bound on the pilot (against " +
                      reference_name + ")";
      return true;
    }
  }
  return false;
}

// The full model: the exponential method where it is the reference or meets the bound with its
// contacts closed, else dopri5.
void chooseFull(const std::vector<double>& exponential, const std::vector<double>& reference,
                bool exponential_closed, bool exponential_reference, double error_bound,
                AutoChoice& choice) {
  if (choice.exponential) {
    bool chosen = exponential_reference;
    if (chosen) {
      choice.pilot_errors.emplace_back("exponential (the reference)", 0.0);
    } else if (exponential_closed) {
      chosen = accept(choice, "exponential", rmsError(exponential, reference),
                      error_bound);  // bound below its own accuracy claim
    }
    if (chosen) {
      choice.method = IntegratorMethod::kExponential;
      choice.reason =
          "full model, exact exponential propagation (contacts closed through the pilot; set-up "
          "and run "
          "predicted cheaper than dopri5's)";
      return;
    }
    if (!exponential_closed)
      choice.pilot_errors.emplace_back("exponential (a contact opened in the pilot)", INFINITY);
    choice.exponential.reset();
  }
  choice.method = IntegratorMethod::kDopri5;
  choice.reason = "full model with dopri5 (events located) at rtol = bound / 100";
}

}  // namespace

AutoChoice chooseAutomatically(const GearRotorModel& model, double t0, const State6& y0,
                               double interval, double pilot_duration, double error_bound,
                               double run_duration, const IntegratorScale& scale) {
  requirePositive("error_bound", error_bound);
  requirePositive("pilot_duration", pilot_duration);
  requireNonNegative("run_duration", run_duration);
  requirePositive("scale.displacement", scale.displacement);
  requirePositive("scale.max_step", scale.max_step);
  requirePositive("scale.divergence_limit", scale.divergence_limit);
  AutoChoice choice;
  choice.scale = scale;
  // At least four output samples, or the comparison would be on the start state alone.
  choice.pilot_duration = std::max(4.0, std::round(pilot_duration / interval)) * interval;
  const double t_end = t0 + choice.pilot_duration;
  const Pilot pilot{model, t0, y0, t_end, interval};

  // dopri5 at rtol = bound / 100: the last candidate, the reference where the exponential method
  // is not one, and the count of steps that predicts its cost over the run. Where the exponential
  // method may become the reference (docs/model.md "Speed against error"), the count comes from
  // the pilot's first kDopriCountSamples output samples alone, and dopri5 runs the whole pilot,
  // from the start again, only where it must be the reference after all.
  choice.relative_tolerance = std::max(error_bound / 100.0, 1e-11);
  const IntegratorOptions dopri =
      autoOptions(IntegratorMethod::kDopri5, choice.relative_tolerance, scale);
  const RigExcitation* rig = model.rigExcitation();
  const GearRotorParameters& p = model.parameters();
  const bool linear_possible =
      rig && p.bearing_clearance[0] <= 0.0 && p.bearing_clearance[1] <= 0.0;
  const bool may_be_reference = linear_possible && error_bound >= kExponentialReferenceBound;
  const double count_duration = may_be_reference
                                    ? std::min(choice.pilot_duration, kDopriCountSamples * interval)
                                    : choice.pilot_duration;
  IntegrationStats dopri_stats;
  std::vector<double> reference;
  const bool whole_pilot_counted = count_duration >= choice.pilot_duration;
  const auto dopriPilot = [&] {
    return deltas(model, [&](const Observer& o) {
      integrate(model, IntegratorMethod::kDopri5, dopri, t0, y0, t_end, interval, o, &dopri_stats);
    });
  };
  if (whole_pilot_counted) {
    reference = dopriPilot();
  } else {
    integrate(model, IntegratorMethod::kDopri5, dopri, t0, y0, t0 + count_duration, interval,
              nullptr, &dopri_stats);
  }
  choice.dopri_pilot_steps = dopri_stats.steps;
  std::string reference_name = "dopri5";

  // The exponential method, its contacts closed through the pilot, is a better reference than
  // dopri5 at bound / 100 for bounds >= kExponentialReferenceBound.
  bool exponential_closed = false;
  std::vector<double> exponential;
  if (linear_possible) {
    exponential = exponentialPilot(pilot, run_duration, dopri_stats.steps, count_duration, choice,
                                   exponential_closed);
  }
  const bool exponential_reference =
      exponential_closed && error_bound >= kExponentialReferenceBound;
  if (exponential_reference) {
    reference = exponential;
    reference_name = "exponential";
  } else if (!whole_pilot_counted) {
    reference = dopriPilot();  // the whole pilot from the start
    choice.dopri_pilot_steps += dopri_stats.steps;
  }
  if (rig && chooseReduced(pilot, reference, reference_name, error_bound, choice)) return choice;
  chooseFull(exponential, reference, exponential_closed, exponential_reference, error_bound,
             choice);
  return choice;
}

State6 integrateChoice(const GearRotorModel& model, const AutoChoice& choice, double t0,
                       const State6& y0, double t_end, double interval, const Observer& observe,
                       IntegrationStats* stats) {
  if (choice.fidelity != Fidelity::kFull)
    return integrateReduced(model, choice.fidelity, t0, y0, t_end, interval, observe);
  const IntegratorOptions o = autoOptions(choice.method, choice.relative_tolerance, choice.scale);
  if (choice.method == IntegratorMethod::kExponential && choice.exponential) {
    return choice.exponential->run(y0, t_end, observe, o,
                                   stats);  // the pilot's propagators, built once
  }
  return integrate(model, choice.method, o, t0, y0, t_end, interval, observe, stats);
}

}  // namespace drivetrain_stiffness

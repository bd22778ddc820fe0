#include "drivetrain_stiffness/core/dynamics/integrators.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/enum_names.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

void checkState(const State6& y, double t, double h, IntegratorMethod method,
                const IntegratorOptions& o) {
  if (!y.allFinite() || y.head<3>().cwiseAbs().maxCoeff() > o.divergence_limit) {
    throw UnstableIntegration(std::string("integrator ") + toString(method) + " diverged at t = " +
                              formatValue(t) + " s with step " + formatValue(h) +
                              " s: the step is beyond the stability limit of the "
                              "stiffest mode (explicit methods: h < 2.79 / omega_max) or the model "
                              "has no bounded response");
  }
}

// Output grid: observe every grid time t0 + k interval in (previous step end, t_next], evaluated
// by `value` (the state, or the dense output inside a step).
template <typename Value>
void emit(double t_next, double t0, double interval, long& next_index, const Observer& observe,
          Value value) {
  for (double t_out = t0 + next_index * interval; t_out <= t_next + 1e-9 * interval;
       t_out = t0 + next_index * interval) {
    observe(t_out, value(std::min(t_out, t_next)));
    ++next_index;
  }
}

long fixedStepCount(double span, double h, double interval, long* per_output) {
  const double n_out = interval / h;
  *per_output = std::lround(n_out);
  if (*per_output < 1 || std::abs(n_out - *per_output) > 1e-6 * n_out) {
    throwInvalid("output_interval", interval,
                 "must be a whole multiple of the step " + formatValue(h));
  }
  const double n = span / h;
  if (std::abs(n - std::round(n)) > 1e-6 * std::max(1.0, n)) {
    throwInvalid("duration", span, "must be a whole multiple of the step " + formatValue(h));
  }
  return std::lround(n);
}

// ---- Dormand-Prince 5(4) coefficients (Dormand & Prince, J. Comput. Appl. Math. 6 (1980) 19;
// dense output after Hairer, Norsett & Wanner, Solving ODEs I, sec. II.6, routine DOPRI5). ----
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                 a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                 a65 = -5103.0 / 18656;
constexpr double a71 = 35.0 / 384, a73 = 500.0 / 1113, a74 = 125.0 / 192, a75 = -2187.0 / 6784,
                 a76 = 11.0 / 84;
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                 e6 = 22.0 / 525, e7 = -1.0 / 40;
constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                 d4 = -10690763975.0 / 1880347072, d5 = 701980252875.0 / 199316789632,
                 d6 = -1453857185.0 / 822651844, d7 = 69997945.0 / 29380423;

struct DenseStep {
  State6 r1, r2, r3, r4, r5;
  double t = 0.0, h = 0.0;
  State6 at(double time) const {
    const double s = (time - t) / h, s1 = 1.0 - s;
    return r1 + s * (r2 + s1 * (r3 + s * (r4 + s1 * r5)));
  }
};

class Dopri5 {
 public:
  Dopri5(const GearRotorModel& m, const IntegratorOptions& o, IntegrationStats& st)
      : m_(m), o_(o), st_(st) {}

  // One attempted step of size h from (t, y) with k1 = f(t, y). Fills y_new, k7 = f(t+h, y_new),
  // the dense output and returns the scaled error norm. `ends_on_switch`: the step ends exactly on
  // a jump of the right-hand side; its last stages are evaluated just before it, on the side the
  // step belongs to.
  double attempt(double t, const State6& y, const State6& k1, double h, State6& y_new, State6& k7,
                 DenseStep& dense, bool ends_on_switch = false) {
    State6 k2, k3, k4, k5, k6;
    const double t_end = ends_on_switch ? std::nextafter(t + h, t) : t + h;
    m_.rhs(t + c2 * h, y + h * a21 * k1, k2);
    m_.rhs(t + c3 * h, y + h * (a31 * k1 + a32 * k2), k3);
    m_.rhs(t + c4 * h, y + h * (a41 * k1 + a42 * k2 + a43 * k3), k4);
    m_.rhs(t + c5 * h, y + h * (a51 * k1 + a52 * k2 + a53 * k3 + a54 * k4), k5);
    m_.rhs(t_end, y + h * (a61 * k1 + a62 * k2 + a63 * k3 + a64 * k4 + a65 * k5), k6);
    y_new = y + h * (a71 * k1 + a73 * k3 + a74 * k4 + a75 * k5 + a76 * k6);
    m_.rhs(t_end, y_new, k7);
    st_.rhs_evaluations += 6;
    const State6 err = h * (e1 * k1 + e3 * k3 + e4 * k4 + e5 * k5 + e6 * k6 + e7 * k7);
    dense.t = t;
    dense.h = h;
    dense.r1 = y;
    dense.r2 = y_new - y;
    dense.r3 = h * k1 - dense.r2;
    dense.r4 = dense.r2 - h * k7 - dense.r3;
    dense.r5 = h * (d1 * k1 + d3 * k3 + d4 * k4 + d5 * k5 + d6 * k6 + d7 * k7);
    double sum = 0.0;
    for (int i = 0; i < 6; ++i) {
      const double scale = o_.absolute_tolerance * (i < 3 ? 1.0 : vel_scale_) +
                           o_.relative_tolerance * std::max(std::abs(y[i]), std::abs(y_new[i]));
      sum += (err[i] / scale) * (err[i] / scale);
    }
    return std::sqrt(sum / 6.0);
  }

  void setVelocityScale(double s) { vel_scale_ = s; }

 private:
  const GearRotorModel& m_;
  const IntegratorOptions& o_;
  IntegrationStats& st_;
  double vel_scale_ = 1.0;
};

ContactRegime regimeAt(const GearRotorModel& m, double t, const State6& y) {
  return m.forces(t, y).regime;
}

}  // namespace

namespace {
constexpr EnumName<IntegratorMethod> kIntegratorMethods[] = {
    {IntegratorMethod::kRk4, "rk4"},
    {IntegratorMethod::kTrapezoidal, "trapezoidal"},
    {IntegratorMethod::kDopri5, "dopri5"},
    {IntegratorMethod::kExponential, "exponential"}};
}  // namespace

IntegratorMethod parseIntegratorMethod(const std::string& field, const std::string& text) {
  return parseEnum(kIntegratorMethods, field, text);
}
const char* toString(IntegratorMethod m) { return enumName(kIntegratorMethods, m); }

namespace {

// Trapezoidal step y1 = y0 + h/2 (f(t, y0) + f(t + h, y1)): Newton on
// g(y1) = y1 - y0 - h/2 (f0 + f(y1)), from an explicit Euler predictor.
void trapezoidalStep(const GearRotorModel& model, double t, double h, State6& y, State6& k1,
                     State6& k2, IntegrationStats& stats) {
  model.rhs(t, y, k1);
  State6 y1 = y + h * k1;  // explicit Euler predictor
  // The forces are piecewise linear and the Jacobian exact within a contact regime, so Newton
  // ends in one or two iterations unless the step crosses a contact change.
  bool converged = false;
  for (int it = 0; it < 12 && !converged; ++it) {
    model.rhs(t + h, y1, k2);
    const State6 g = y1 - y - 0.5 * h * (k1 + k2);
    const Matrix6 a = Matrix6::Identity() - 0.5 * h * model.jacobian(t + h, y1);
    const State6 dy = a.partialPivLu().solve(-g);
    y1 += dy;
    ++stats.newton_iterations;
    stats.rhs_evaluations += 2;
    const double scale = 1e-14 * (y1.head<3>().cwiseAbs().maxCoeff() + 1e-15);
    const double vscale = 1e-14 * (y1.tail<3>().cwiseAbs().maxCoeff() + 1e-12);
    converged =
        dy.head<3>().cwiseAbs().maxCoeff() <= scale && dy.tail<3>().cwiseAbs().maxCoeff() <= vscale;
  }
  // A contact change inside the step can make Newton cycle between regimes: the step is kept
  // (bounded) but counted, so a caller can see how often it happened.
  if (!converged) ++stats.newton_failures;
  y = y1;
}

// rk4 or the trapezoidal rule at the fixed step o.step from (t0, y) to t_end.
State6 integrateFixed(const GearRotorModel& model, IntegratorMethod method,
                      const IntegratorOptions& o, double t0, State6 y, double t_end,
                      double interval, const Observer& observe, IntegrationStats& stats) {
  long per_output = 1;
  const double h = o.step;
  const long n = fixedStepCount(t_end - t0, h, interval, &per_output);
  State6 k1, k2, k3, k4;
  for (long i = 0; i < n; ++i) {
    const double t = t0 + i * h;  // no accumulated round-off in t
    if (method == IntegratorMethod::kRk4) {
      model.rhs(t, y, k1);
      model.rhs(t + 0.5 * h, y + 0.5 * h * k1, k2);
      model.rhs(t + 0.5 * h, y + 0.5 * h * k2, k3);
      model.rhs(t + h, y + h * k3, k4);
      y += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      stats.rhs_evaluations += 4;
    } else {
      trapezoidalStep(model, t, h, y, k1, k2, stats);
    }
    ++stats.steps;
    checkState(y, t + h, h, method, o);
    if (observe && (i + 1) % per_output == 0) observe(t0 + (i + 1) * h, y);
  }
  return y;
}

// Velocities are compared with displacements through the fastest natural scale: omega_ref =
// sqrt(k/m).
double velocityScale(const GearRotorModel& model, double t0) {
  MeshInstant mi;
  model.meshAt(t0, mi);
  const GearRotorParameters& p = model.parameters();
  const double k_ref =
      std::max({mi.k_drive + mi.k_back, p.bearing_stiffness[0], p.bearing_stiffness[1], 1.0});
  const double m_ref = std::min({model.equivalentMass(), p.pinion_mass, p.gear_mass});
  return std::sqrt(k_ref / m_ref);
}

// A rejected dopri5 step of h_try [s] at t [s]: the step to try next; UnstableIntegration where
// h_try is already the smallest.
double rejectedStep(double err, double h_try, double tiny, double t, IntegrationStats& st) {
  ++st.rejected;
  if (h_try <= tiny) {
    throw UnstableIntegration(
        "integrator dopri5: step size underflow at t = " + formatValue(t) +
        " s (the error test fails at the smallest step " + formatValue(h_try) +
        " s; tolerances too tight for double precision, or a discontinuity the step cannot "
        "resolve)");
  }
  if (!std::isfinite(err)) return 0.1 * h_try;
  return h_try * std::max(0.2, 0.9 * std::pow(err, -0.2));
}

// An accepted step from (t, y) to (t_new, y_new) whose contact regime changed: the earliest change
// on the dense output, by bisection in time, and the step redone up to it (so no step straddles
// the kink; the next step starts on it).
void locateContactChange(const GearRotorModel& model, Dopri5& dp, double t, const State6& y,
                         const State6& k1, State6& y_new, State6& k7, DenseStep& dense,
                         double& h_try, double& t_new, bool& hits_switch, IntegrationStats& st) {
  const ContactRegime r0 = regimeAt(model, t, y);
  if (regimeAt(model, t_new, y_new) == r0) return;
  double lo = t, hi = t_new;
  for (int i = 0; i < 60 && hi - lo > 1e-14 * std::max(1.0, std::abs(t)); ++i) {
    const double mid = 0.5 * (lo + hi);
    if (regimeAt(model, mid, dense.at(mid)) == r0)
      lo = mid;
    else
      hi = mid;
  }
  if (hi - t > 1e-9 * h_try) {
    const double h_event = hi - t;
    dp.attempt(t, y, k1, h_event, y_new, k7, dense);
    hits_switch = false;
    t_new = t + h_event;
    h_try = h_event;
    ++st.events;
  }
}

// dopri5 from (t0, y) to t_end, observing the grid from index next_out on.
State6 integrateDopri5(const GearRotorModel& model, const IntegratorOptions& o, double t0, State6 y,
                       double t_end, double interval, const Observer& observe, long next_out,
                       IntegrationStats& st) {
  Dopri5 dp(model, o, st);
  dp.setVelocityScale(velocityScale(model, t0));
  double t = t0, h = std::min(o.step, o.max_step);
  State6 k1, y_new, k7;
  model.rhs(t, y, k1);
  ++st.rhs_evaluations;
  DenseStep dense;
  double err_prev = 1e-4;
  long switches_in_place = 0;
  while (t < t_end) {
    if (o.max_steps > 0 && st.steps + st.rejected > o.max_steps) {
      throw UnstableIntegration("integrator dopri5: more than " + std::to_string(o.max_steps) +
                                " steps from t = " + formatValue(t0) + " s to " +
                                formatValue(t_end) + " s (stopped at " + formatValue(t) +
                                " s): the work bound of one call");
    }
    const double switch_time = model.nextSwitch(t);
    double h_try = std::min({h, o.max_step, t_end - t});
    bool hits_switch = false;
    if (switch_time - t <= h_try) {
      h_try = switch_time - t;
      hits_switch = true;
    }
    const double tiny = 64.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t));
    if (h_try < tiny) {
      if (hits_switch) {  // already on the switch (to rounding): step onto it, restart the stages
        // An excitation whose next switch never gets past rounding would loop here for ever.
        if (++switches_in_place > 1000000) {
          throw UnstableIntegration(
              "integrator dopri5: the excitation's switch events stopped advancing at t = " +
              formatValue(t) + " s");
        }
        t = switch_time;
        model.rhs(t, y, k1);
        continue;
      }
      if (t_end - t < tiny) break;  // at the end (to rounding)
      h_try = tiny;  // a step shrunk by an event right at the step start: take the smallest step,
                     // never skip
    }
    const double err = dp.attempt(t, y, k1, h_try, y_new, k7, dense, hits_switch);
    if (!(err <= 1.0)) {
      h = rejectedStep(err, h_try, tiny, t, st);
      continue;
    }
    double t_new = t + h_try;
    if (o.locate_events)
      locateContactChange(model, dp, t, y, k1, y_new, k7, dense, h_try, t_new, hits_switch, st);
    checkState(y_new, t_new, h_try, IntegratorMethod::kDopri5, o);
    if (observe)
      emit(t_new, t0, interval, next_out, observe, [&](double tq) { return dense.at(tq); });
    t = hits_switch ? switch_time : t_new;  // land exactly on the switch
    y = y_new;
    k1 = k7;
    ++st.steps;
    if (hits_switch) {
      // A tooth entered or left: the right-hand side jumps and k7 was taken on the old side.
      model.rhs(t, y, k1);
      ++st.rhs_evaluations;
      ++st.events;
    }
    // PI controller (Hairer et al., sec. IV.2): h_new = h err^-0.7/5 err_prev^0.4/5.
    const double e = std::max(err, 1e-10);
    const double fac = 0.9 * std::pow(e, -0.14) * std::pow(err_prev, 0.08);
    h = h_try * std::clamp(fac, 0.2, 10.0);
    err_prev = e;
  }
  return y;
}

}  // namespace

State6 integrate(const GearRotorModel& model, IntegratorMethod method, const IntegratorOptions& o,
                 double t0, const State6& y0, double t_end, double interval,
                 const Observer& observe, IntegrationStats* stats_out) {
  requireFinite("t0", t0);
  requireFinite("t_end", t_end);
  if (!(t_end >= t0))
    throwInvalid("t_end", t_end,
                 "must be >= t0 = " + formatValue(t0) + " (time must not run backwards)");
  requirePositive("output_interval", interval);
  requirePositive("step", o.step);
  if (!y0.allFinite()) throw InvalidInput("initial state: contains a non-finite value");
  if (method == IntegratorMethod::kExponential) {
    const PeriodicExponentialPropagator propagator(model, t0, interval, o.magnus_step_factor);
    return propagator.run(y0, t_end, observe, o, stats_out);
  }
  IntegrationStats stats;
  long next_out = 0;
  if (observe) {
    observe(t0, y0);
    next_out = 1;
  }
  const State6 y =
      method == IntegratorMethod::kRk4 || method == IntegratorMethod::kTrapezoidal
          ? integrateFixed(model, method, o, t0, y0, t_end, interval, observe, stats)
          : integrateDopri5(model, o, t0, y0, t_end, interval, observe, next_out, stats);
  if (stats_out) *stats_out = stats;
  return y;
}

}  // namespace drivetrain_stiffness

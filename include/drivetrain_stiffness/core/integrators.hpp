// Time integration of the gear-rotor model. Three methods, each with the same contract:
//  - rk4: classical fixed-step Runge-Kutta (explicit; stable for h < 2.79 / omega_max).
//  - trapezoidal: implicit trapezoidal rule with Newton iterations (A-stable, second order; for a
//    linear undamped system it conserves the quadratic energy exactly), fixed step, stable with
//    steps far longer than the stiffest period.
//  - dopri5: Dormand & Prince (1980) 5(4) embedded pair with PI step control, FSAL, Hairer's
//    fourth-order dense output; tooth-count switches are hit exactly (time events), contact
//    changes (flank lift-off, bearing clearance) are located on the dense output and the step is
//    redone up to them (state events). The reference method.
//  - exponential: exact-exponential propagation in the linear regime (exponential_integrator.hpp),
//    for scenes whose contacts stay closed; hands over to dopri5 if one opens.
// Every method checks each step: a non-finite state or a state beyond `divergence_limit` throws
// UnstableIntegration naming the method, the step and the time, never returns NaN.
#pragma once

#include <functional>
#include <string>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/core/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

enum class IntegratorMethod { kRk4, kTrapezoidal, kDopri5, kExponential };
IntegratorMethod parseIntegratorMethod(const std::string& field, const std::string& text);
const char* toString(IntegratorMethod method);

/// The integration diverged or ran out of steps (one of the library's own errors, errors.hpp).
class UnstableIntegration : public Error {
 public:
  using Error::Error;
};

struct IntegratorOptions {
  double step = 1e-6;  ///< fixed step h [s] (rk4, trapezoidal); initial step for dopri5
  double relative_tolerance = 1e-8;  ///< dopri5
  double absolute_tolerance =
      1e-12;               ///< dopri5, on displacements [m] (velocities scaled by omega_ref)
  double max_step = 1e-3;  ///< dopri5 [s]
  double divergence_limit = 1e-2;   ///< |displacement| beyond this [m] counts as blow-up
  bool locate_events = true;        ///< dopri5: locate contact changes
  double magnus_step_factor = 1.0;  ///< exponential: Magnus step <= factor / omega_max
  /// dopri5: more accepted plus rejected steps than this in one call throw UnstableIntegration
  /// (0: no bound). The online estimator bounds its fallback so that no input stalls the caller.
  long max_steps = 0;
};

/// The units a model's state is in, as the integrators' tolerances and limits need them: SI (the
/// rig: metres and seconds) or the dimensionless oscillators (kahraman_singh, chaotic: the unit
/// gap, time in units of 1/omega_n). The library's defaults are SI; a dimensionless state of O(1)
/// is 100 times past the SI divergence limit at its first step.
struct IntegratorScale {
  double displacement = 1e-6;      ///< absolute tolerance per unit relative tolerance: ~1 um [m]
  double max_step = 1e-4;          ///< dopri5's longest step [s]
  double divergence_limit = 1e-2;  ///< |displacement| beyond this counts as blow-up [m]
  /// The dimensionless oscillators: a hundredth of the unit gap, a tenth of the natural period's
  /// 1/2pi, a thousand gaps.
  static IntegratorScale dimensionless() { return {1e-2, 0.1, 1e3}; }
};

struct IntegrationStats {
  long steps = 0, rejected = 0, rhs_evaluations = 0, events = 0, newton_iterations = 0;
  long fallbacks = 0;           ///< exponential: runs handed to dopri5 when a contact opened
  long newton_failures = 0;     ///< trapezoidal: steps whose Newton iteration did not converge
  double fallback_from = -1.0;  ///< time of that hand-over [s], -1 if none
};

/// Called at each output time with the state.
using Observer = std::function<void(double t, const State6& y)>;

/// Integrates from (t0, y0) to t_end, calling `observe` at t0 and at every multiple of
/// output_interval after t0 (the fixed-step methods need output_interval to be a multiple of
/// their step). Returns the final state.
State6 integrate(const GearRotorModel& model, IntegratorMethod method,
                 const IntegratorOptions& options, double t0, const State6& y0, double t_end,
                 double output_interval, const Observer& observe,
                 IntegrationStats* stats = nullptr);

}  // namespace drivetrain_stiffness

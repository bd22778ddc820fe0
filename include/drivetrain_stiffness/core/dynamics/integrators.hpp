// rk4, trapezoidal, dopri5 (Dormand & Prince, J. Comput. Appl. Math. 6 (1980) 19), exponential
// (docs/model.md "Integration methods").
#pragma once

#include <functional>
#include <string>

#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

enum class IntegratorMethod { kRk4, kTrapezoidal, kDopri5, kExponential };
IntegratorMethod parseIntegratorMethod(const std::string& field, const std::string& text);
const char* toString(IntegratorMethod method);

/// The integration diverged or ran out of steps.
class UnstableIntegration : public Error {
 public:
  using Error::Error;
};

struct IntegratorOptions {
  double step = 1e-6;  ///< [s] fixed, or dopri5's first
  double relative_tolerance = 1e-8;
  double absolute_tolerance = 1e-12;  ///< [m]
  double max_step = 1e-3;             ///< [s]
  double divergence_limit = 1e-2;     ///< [m]
  bool locate_events = true;
  double magnus_step_factor = 1.0;  ///< Magnus step <= factor / omega_max
  /// dopri5's steps per call (0: no bound).
  long max_steps = 0;
};

/// The units of a model's state: SI, or the dimensionless oscillators.
struct IntegratorScale {
  double displacement = 1e-6;      ///< absolute per relative tolerance [m]
  double max_step = 1e-4;          ///< [s]
  double divergence_limit = 1e-2;  ///< [m]
  static IntegratorScale dimensionless() { return {1e-2, 0.1, 1e3}; }
};

struct IntegrationStats {
  long steps = 0, rejected = 0, rhs_evaluations = 0, events = 0, newton_iterations = 0;
  long fallbacks = 0;  ///< exponential: hand-overs to dopri5
  long newton_failures = 0;
  double fallback_from = -1.0;  ///< [s], -1 if none
};

/// Called at each output time with the state.
using Observer = std::function<void(double t, const State6& y)>;

/// From (t0, y0) to t_end [s], observing every output_interval [s]; the final state. Throws
/// UnstableIntegration (non-finite, beyond divergence_limit), InvalidInput (bad options).
State6 integrate(const GearRotorModel& model, IntegratorMethod method,
                 const IntegratorOptions& options, double t0, const State6& y0, double t_end,
                 double output_interval, const Observer& observe,
                 IntegrationStats* stats = nullptr);

}  // namespace drivetrain_stiffness

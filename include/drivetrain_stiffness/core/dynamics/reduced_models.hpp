// quasi_static (m_s -> 0), linear_modal (mean stiffness) and `auto` (docs/model.md
// "Integration methods").
#pragma once

#include <memory>
#include <string>

#include "drivetrain_stiffness/core/dynamics/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/dynamics/integrators.hpp"
#include "drivetrain_stiffness/core/dynamics/rig_excitation.hpp"

namespace drivetrain_stiffness {

enum class Fidelity { kFull, kQuasiStatic, kLinearModal };
const char* toString(Fidelity f);
/// "full", "quasi_static" or "linear_modal"; else InvalidInput naming `field`.
Fidelity parseFidelity(const std::string& field, const std::string& text);

/// From (t0, y0) to t_end [s] on the grid [s]. Throws InvalidInput (kFull, no rig excitation).
State6 integrateReduced(const GearRotorModel& model, Fidelity fidelity, double t0, const State6& y0,
                        double t_end, double output_interval, const Observer& observe);

struct AutoChoice {
  Fidelity fidelity = Fidelity::kFull;
  IntegratorMethod method = IntegratorMethod::kDopri5;
  double relative_tolerance = 0.0;
  double pilot_duration = 0.0;                               ///< [s]
  std::vector<std::pair<std::string, double>> pilot_errors;  ///< relative RMS of delta
  long dopri_pilot_steps = 0;
  std::string reason;
  IntegratorScale scale;
  /// Reused by integrateChoice.
  std::shared_ptr<const PeriodicExponentialPropagator> exponential;
};

/// auto's constants (docs/model.md "Bounds, costs and tests of the propagators").
constexpr double kMagnusStepCost = 5.0;
constexpr int kDopriCountSamples = 8;
constexpr double kExponentialReferenceBound = 1e-6;

/// auto's options for `method` in the units of `scale`.
IntegratorOptions autoOptions(IntegratorMethod method, double relative_tolerance,
                              const IntegratorScale& scale = {});

/// The pilot [s]: <= run_duration [s] / 4 and 40 output intervals [s].
double defaultPilotDuration(double run_duration, double output_interval);

/// The cheapest fidelity and method meeting error_bound (relative RMS of delta) over a pilot [s]
/// from (t0 [s], y0); run_duration [s] weighs the set-up (0: long). Throws InvalidInput.
AutoChoice chooseAutomatically(const GearRotorModel& model, double t0, const State6& y0,
                               double output_interval, double pilot_duration, double error_bound,
                               double run_duration = 0.0, const IntegratorScale& scale = {});

/// Runs `choice` from (t0, y0) to t_end [s] on the grid [s].
State6 integrateChoice(const GearRotorModel& model, const AutoChoice& choice, double t0,
                       const State6& y0, double t_end, double output_interval,
                       const Observer& observe, IntegrationStats* stats = nullptr);

}  // namespace drivetrain_stiffness

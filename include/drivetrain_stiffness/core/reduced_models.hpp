// Reduced fidelities of the gear-rotor model, and the `auto` choice among all methods.
//
//  - quasi_static: the torsional mode (tens of kHz) is taken as always in equilibrium: m_s -> 0 in
//    m_s x'' + F = F_drive gives F = F_drive, so delta = F_drive / k_s(phase) (the static TE) and
//    each shaft is a damped oscillator on its bearing driven by -/+ F_drive alone; x follows from
//    delta = x + x_p - x_g - e. Valid when the excitation is far below the torsional mode.
//  - linear_modal: the stiffness held at its mean over a mesh period (no parametric excitation):
//    a linear time-invariant system, propagated exactly by one matrix exponential per output
//    interval (TE generator and first-order-hold torque as in the exponential method).
//  - auto: runs each candidate, cheapest first (quasi_static, linear_modal, exponential when the
//    model can be linear, dopri5 at rtol = bound / 100), over a pilot window, and uses the first
//    whose relative RMS error of delta meets half the bound against the reference: the
//    exponential method where it was built and kept its contacts closed (bound >= 1e-6), dopri5 at
//    rtol = bound / 100 otherwise. The exponential method is built only where its set-up is
//    predicted cheaper than dopri5's work over the run, and then only once, for the pilot and the
//    run.
#pragma once

#include <memory>
#include <string>

#include "drivetrain_stiffness/core/exponential_integrator.hpp"
#include "drivetrain_stiffness/core/integrators.hpp"
#include "drivetrain_stiffness/core/rig_excitation.hpp"

namespace drivetrain_stiffness {

enum class Fidelity { kFull, kQuasiStatic, kLinearModal };
const char* toString(Fidelity f);
/// "full", "quasi_static" or "linear_modal"; anything else throws InvalidInput naming `field`.
Fidelity parseFidelity(const std::string& field, const std::string& text);

/// Integrates a reduced fidelity (the model must use a RigExcitation) on the output grid.
State6 integrateReduced(const GearRotorModel& model, Fidelity fidelity, double t0, const State6& y0,
                        double t_end, double output_interval, const Observer& observe);

struct AutoChoice {
  Fidelity fidelity = Fidelity::kFull;
  IntegratorMethod method = IntegratorMethod::kDopri5;
  double relative_tolerance = 0.0;  ///< for dopri5
  double pilot_duration = 0.0;      ///< [s]
  std::vector<std::pair<std::string, double>>
      pilot_errors;  ///< candidate, relative RMS error of delta
  /// dopri5 steps the choice itself took: the count over kDopriCountSamples, plus the whole pilot
  /// where dopri5 was the reference after all, or the whole pilot alone where the exponential
  /// method could not be the reference (a count, not a clock, of what the choice cost in dopri5).
  long dopri_pilot_steps = 0;
  std::string reason;
  /// The units the choice was made in (chooseAutomatically's `scale`): integrateChoice runs in
  /// them.
  IntegratorScale scale;
  /// The exponential method's propagators built for the pilot (time origin t0, the pilot's output
  /// interval): integrateChoice reuses them, so their setup is paid once.
  std::shared_ptr<const PeriodicExponentialPropagator> exponential;
};

/// The cost of one Magnus step of the exponential method's set-up (an 11x11 matrix exponential)
/// in steps of dopri5 on the same model: `auto`'s exchange rate between the two. Measured with
/// drivetrain_bench (docs/bench.jsonl: setup_s over magnus_steps_per_period against wall_s over
/// steps): 3.6-6.7 us per Magnus step on nominal, torque_steps, near_rigid_bearings and
/// parametric_resonance, against 0.93-1.1 us per dopri5 step.
constexpr double kMagnusStepCost = 5.0;
/// Where the exponential method may become auto's reference, dopri5's cost over the run is
/// predicted from its steps over this many output samples at the pilot's start (or the whole
/// pilot, if shorter), and dopri5 runs the whole pilot only where it is the reference after all
/// (reduced_models.cpp).
constexpr int kDopriCountSamples = 8;
/// The smallest error bound for which the exponential method, its contacts closed through the
/// pilot, serves as the reference (built at Magnus step 1/omega_max, its err_rms_rel against dopri5
/// at rtol 1e-12 is at most 1.2e-8 on the bench scenes: 40x below half this bound). Not step
/// 2/omega_max, although it sets up in 0.65 of the time: that step gives 7.4e-7
/// to 2.4e-6 on the seed rig at 2,490-2,505 rpm with mesh damping ratios 0.05-0.01, where each
/// table piece just fits in one step (1.3e-7 at most at step 1), which would break the bound
/// unseen.
constexpr double kExponentialReferenceBound = 1e-6;

/// The options auto runs `method` with, in its pilot and in the run (dopri5 at
/// `relative_tolerance`), in the model's units (`scale`: SI by default).
IntegratorOptions autoOptions(IntegratorMethod method, double relative_tolerance,
                              const IntegratorScale& scale = {});

/// The pilot auto is given by the CLI, the bench and the tests: a sample of the run, at most a
/// quarter of it (a pilot as long as the run would be the run itself, paid twice) and at most 40
/// output samples [s].
double defaultPilotDuration(double run_duration, double output_interval);

/// Picks the cheapest fidelity and method whose pilot error meets `error_bound` (relative RMS of
/// delta). The pilot covers `pilot_duration` from (t0, y0); `run_duration` [s] is the span the
/// choice will run (it weighs the exponential method's set-up against dopri5's work; 0: unknown,
/// taken as long, so the set-up is worth paying). `scale`: the units of the model's state (SI by
/// default; Scene::scale() gives a scene's), kept in the choice for integrateChoice.
AutoChoice chooseAutomatically(const GearRotorModel& model, double t0, const State6& y0,
                               double output_interval, double pilot_duration, double error_bound,
                               double run_duration = 0.0, const IntegratorScale& scale = {});

/// Runs `choice` (from chooseAutomatically) over the whole span.
State6 integrateChoice(const GearRotorModel& model, const AutoChoice& choice, double t0,
                       const State6& y0, double t_end, double output_interval,
                       const Observer& observe, IntegrationStats* stats = nullptr);

}  // namespace drivetrain_stiffness

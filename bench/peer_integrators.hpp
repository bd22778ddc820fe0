// The integrators a user would otherwise pick, driving the same GearRotorModel right-hand side:
// Boost.odeint runge_kutta_dopri5 (dense output) and rosenbrock4 (with our analytic Jacobian), and
// SUNDIALS CVODE (BDF, Newton with a dense direct solver and our Jacobian). Used only by the
// benchmark, to compare speed against error with our methods on the same scenes.
#pragma once

#include <functional>
#include <string>

#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"

namespace drivetrain_stiffness {
namespace bench {

struct PeerResult {
  long steps = 0;
};

using SampleObserver = std::function<void(double t, const State6& y)>;

/// Integrates from (0, y0) to t_end, observing at multiples of `interval`; relative and absolute
/// tolerances as given (absolute on every component).
PeerResult odeintDopri5(const GearRotorModel& m, const State6& y0, double t_end, double interval,
                        double rtol, double atol, const SampleObserver& observe);
PeerResult odeintRosenbrock4(const GearRotorModel& m, const State6& y0, double t_end,
                             double interval, double rtol, double atol,
                             const SampleObserver& observe);
PeerResult cvodeBdf(const GearRotorModel& m, const State6& y0, double t_end, double interval,
                    double rtol, double atol, const SampleObserver& observe);

}  // namespace bench
}  // namespace drivetrain_stiffness

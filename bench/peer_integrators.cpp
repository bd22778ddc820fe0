#include "peer_integrators.hpp"

#include <array>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/ublas/matrix.hpp>
#include <boost/numeric/ublas/vector.hpp>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

namespace drivetrain_stiffness {
namespace bench {
namespace odeint = boost::numeric::odeint;

namespace {
std::vector<double> outputTimes(double t_end, double interval) {
  std::vector<double> times;
  const long n = std::lround(t_end / interval);
  for (long i = 0; i <= n; ++i) times.push_back(i * interval);
  return times;
}
}  // namespace

PeerResult odeintDopri5(const GearRotorModel& m, const State6& y0, double t_end, double interval,
                        double rtol, double atol, const SampleObserver& observe) {
  using State = std::array<double, 6>;
  State x;
  for (int i = 0; i < 6; ++i) x[i] = y0[i];
  PeerResult r;
  auto system = [&](const State& s, State& d, double t) {
    State6 y, dy;
    for (int i = 0; i < 6; ++i) y[i] = s[i];
    m.rhs(t, y, dy);
    for (int i = 0; i < 6; ++i) d[i] = dy[i];
  };
  const std::vector<double> times = outputTimes(t_end, interval);
  r.steps = static_cast<long>(odeint::integrate_times(
      odeint::make_dense_output(atol, rtol, odeint::runge_kutta_dopri5<State>()), system, x,
      times.begin(), times.end(), interval * 0.5, [&](const State& s, double t) {
        State6 y;
        for (int i = 0; i < 6; ++i) y[i] = s[i];
        observe(t, y);
      }));
  return r;
}

PeerResult odeintRosenbrock4(const GearRotorModel& m, const State6& y0, double t_end,
                             double interval, double rtol, double atol,
                             const SampleObserver& observe) {
  using Vector = boost::numeric::ublas::vector<double>;
  using Matrix = boost::numeric::ublas::matrix<double>;
  Vector x(6);
  for (int i = 0; i < 6; ++i) x[i] = y0[i];
  auto rhs = [&](const Vector& s, Vector& d, double t) {
    State6 y, dy;
    for (int i = 0; i < 6; ++i) y[i] = s[i];
    m.rhs(t, y, dy);
    for (int i = 0; i < 6; ++i) d[i] = dy[i];
  };
  auto jac = [&](const Vector& s, Matrix& j, double t, Vector& dfdt) {
    State6 y, f1, f2;
    for (int i = 0; i < 6; ++i) y[i] = s[i];
    const Matrix6 a = m.jacobian(t, y);
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) j(r, c) = a(r, c);
    const double h = 1e-9 * std::max(1e-6, std::abs(t));  // explicit time dependence (excitation)
    m.rhs(t + h, y, f1);
    m.rhs(t - h, y, f2);
    for (int i = 0; i < 6; ++i) dfdt[i] = (f1[i] - f2[i]) / (2 * h);
  };
  PeerResult r;
  const std::vector<double> times = outputTimes(t_end, interval);
  r.steps = static_cast<long>(
      odeint::integrate_times(odeint::make_dense_output(atol, rtol, odeint::rosenbrock4<double>()),
                              std::make_pair(rhs, jac), x, times.begin(), times.end(),
                              interval * 0.5, [&](const Vector& s, double t) {
                                State6 y;
                                for (int i = 0; i < 6; ++i) y[i] = s[i];
                                observe(t, y);
                              }));
  return r;
}

namespace {
struct CvodeUser {
  const GearRotorModel* model;
};

int cvodeRhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
  const auto* u = static_cast<CvodeUser*>(user);
  State6 s, d;
  for (int i = 0; i < 6; ++i) s[i] = NV_Ith_S(y, i);
  u->model->rhs(t, s, d);
  for (int i = 0; i < 6; ++i) NV_Ith_S(ydot, i) = d[i];
  return 0;
}

int cvodeJac(sunrealtype t, N_Vector y, N_Vector, SUNMatrix j, void* user, N_Vector, N_Vector,
             N_Vector) {
  const auto* u = static_cast<CvodeUser*>(user);
  State6 s;
  for (int i = 0; i < 6; ++i) s[i] = NV_Ith_S(y, i);
  const Matrix6 a = u->model->jacobian(t, s);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) SM_ELEMENT_D(j, r, c) = a(r, c);
  return 0;
}
}  // namespace

PeerResult cvodeBdf(const GearRotorModel& m, const State6& y0, double t_end, double interval,
                    double rtol, double atol, const SampleObserver& observe) {
  SUNContext ctx = nullptr;
  if (SUNContext_Create(nullptr, &ctx) != 0)
    throw std::runtime_error("CVODE: SUNContext_Create failed");
  N_Vector y = N_VNew_Serial(6, ctx);
  for (int i = 0; i < 6; ++i) NV_Ith_S(y, i) = y0[i];
  void* mem = CVodeCreate(CV_BDF, ctx);
  CvodeUser user{&m};
  SUNMatrix a = SUNDenseMatrix(6, 6, ctx);
  SUNLinearSolver ls = SUNLinSol_Dense(y, a, ctx);
  int flag = CVodeInit(mem, cvodeRhs, 0.0, y);
  flag |= CVodeSStolerances(mem, rtol, atol);
  flag |= CVodeSetUserData(mem, &user);
  flag |= CVodeSetLinearSolver(mem, ls, a);
  flag |= CVodeSetJacFn(mem, cvodeJac);
  flag |= CVodeSetMaxNumSteps(mem, 100000000);
  if (flag != 0) throw std::runtime_error("CVODE: setup failed");
  observe(0.0, y0);
  const long n = std::lround(t_end / interval);
  for (long i = 1; i <= n; ++i) {
    sunrealtype t = 0.0;
    if (CVode(mem, i * interval, y, &t, CV_NORMAL) < 0)
      throw std::runtime_error("CVODE: integration failed");
    State6 s;
    for (int k = 0; k < 6; ++k) s[k] = NV_Ith_S(y, k);
    observe(i * interval, s);
  }
  long steps = 0;
  CVodeGetNumSteps(mem, &steps);
  CVodeFree(&mem);
  SUNLinSolFree(ls);
  SUNMatDestroy(a);
  N_VDestroy(y);
  SUNContext_Free(&ctx);
  PeerResult r;
  r.steps = steps;
  return r;
}

}  // namespace bench
}  // namespace drivetrain_stiffness

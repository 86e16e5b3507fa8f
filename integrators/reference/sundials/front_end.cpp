#include "integrators/reference/sundials/front_end.hpp"

#include <cmath>
#include <cstdlib>
#include <iostream>

namespace stiffbench::sundials_detail {

void SundialsFrontEnd::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  adapter_.reset(sys, info().name, set_, needs_linear_solver(), t0, y0, uses_implicit_part(sys));
  t_ = t0;
  y_last_ = y0;
  fixed_h_ = 0;
  fixed_mode_ = false;
  free_memory();
  // The library copies y0 into its own vectors; the wrapper only lends it the data.
  N_Vector y = N_VMake_Serial(adapter_.size(), const_cast<double*>(y0.data()), ctx_);
  SolveStats dummy;
  auto ok = [&](int flag, const char* what) {
    if (!check(flag, what, dummy)) throw std::runtime_error(dummy.message);
  };
  create(t0, y, ok);
  if (needs_linear_solver()) {
    adapter_.create_linear_solver(y, ctx_);
    attach_linear_solver(ok);
  }
  N_VDestroy(y);
}

Status SundialsFrontEnd::advance_to(const OdeSystem& sys, double t_out, VecRef y,
                                    SolveStats& stats) {
  sync(sys, t_, y);
  // Step exactly to t_out instead of stepping past it and interpolating: ARKODE's dense
  // output at tolerances near 1e-8 was measured to be off by 1e-5 on y' = (-1+3i)y.
  if (!check(set_stop_time(t_out), "SetStopTime", stats)) return Status::solver_error;
  return evolve(t_out, y, false, stats);
}

Status SundialsFrontEnd::fixed_step(const OdeSystem& sys, double t, VecRef y, double h,
                                    SolveStats& stats, int (*set_fixed_step)(void*, sunrealtype)) {
  sync(sys, t, y);
  if (h != fixed_h_) {
    if (!check(set_fixed_step(mem_, h), "ARKStepSetFixedStep", stats)) return Status::solver_error;
    fixed_h_ = h;
  }
  fixed_mode_ = true;
  return evolve(t + h, y, true, stats);
}

bool SundialsFrontEnd::check(int flag, const char* what, SolveStats& stats) {
  if (flag >= 0) return true;
  // The library allocates the flag name; the caller frees it.
  char* name = flag_name(flag);
  const std::string& lib = adapter_.library_error();
  stats.message = std::string(what) + " failed: " + (name ? name : "unknown flag") +
                  (lib.empty() ? "" : " (" + lib + ")");
  std::free(name);
  if (!adapter_.callback_error().empty()) stats.message += "; " + adapter_.callback_error();
  std::cerr << "stiffbench: " << info().name << ": " << stats.message << "\n";
  return false;
}

void SundialsFrontEnd::sync(const OdeSystem& sys, double t, CVecRef y) {
  if (&sys != adapter_.system())
    throw std::logic_error("SUNDIALS integrator: system differs from reset()");
  // The driver computes t0 + k·h while the library accumulates: equal up to rounding.
  if (std::abs(t - t_) <= 1e-13 * std::max(1.0, std::abs(t)) && y == y_last_) return;
  N_Vector yw = N_VMake_Serial(adapter_.size(), const_cast<double*>(y.data()), ctx_);
  reinit(t, yw);
  N_VDestroy(yw);
  t_ = t;
}

Status SundialsFrontEnd::evolve(double t_out, VecRef y, bool one_step, SolveStats& stats) {
  adapter_.clear_errors();
  // The driver's storage: no copy.
  N_Vector yout = N_VMake_Serial(adapter_.size(), y.data(), ctx_);
  sunrealtype tret = t_;
  const int flag = solve(t_out, yout, &tret, one_step);
  N_VDestroy(yout);
  read_counters(stats);
  adapter_.rethrow();
  if (!check(flag, solve_name(), stats)) return Status::solver_error;
  t_ = tret;
  y_last_ = y;
  return Status::ok;
}

void SundialsFrontEnd::read_counters(SolveStats& s) {
  const Counters c = counters(s);
  if (!fixed_mode_) s.steps = c.steps;  // the fixed-step driver counts its own steps
  s.error_test_failures = c.etf;
  s.newton_iters = c.nni;
  s.newton_conv_failures = c.ncf;
  s.linear_setups = c.nsetups;
  s.lin_solves = needs_linear_solver() ? c.nni : 0;  // one linear solve per Newton iteration
  s.linear_iters = c.nli;
  // Analytic Jacobians through OdeSystem::jacobian() are counted at the system boundary,
  // force_jacobians() calls here; difference-quotient ones are the library's count.
  s.jac_evals = adapter_.use_analytic() ? adapter_.force_jacobian_evals() : c.nje;
  s.library_f_evals = c.nfe + c.nfi + c.nfels;
  if (needs_linear_solver())
    s.library_report =
        "Linear solver                = " + adapter_.linear_solver_note() + "\n" + s.library_report;
}

}  // namespace stiffbench::sundials_detail

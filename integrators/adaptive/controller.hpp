// The step-size controller shared by every hand-written adaptive method (embedded explicit
// pairs, radau5): error norm, PI control, first-step heuristic and the loop that advances to an
// output time. The stepper computes a trial step and its error estimate; the controller maps
// (h, error) to accept/reject and the next h; advance_adaptive() owns the loop (docs/design.md).
//
// Error norm (Hairer–Nørsett–Wanner I §II.4, eq. (4.11); SUNDIALS' WRMS norm):
//   err = sqrt( (1/n) Σ_i (e_i / sc_i)² ),   sc_i = atol + rtol · max(|y_n,i|, |y_n+1,i|),
// a step is accepted when err ≤ 1.
//
// Step-size choice with k = (order of the error estimate) + 1, i.e. e = O(h^k):
//   accepted step:  h_new = h · clamp(safety · err_n^(-α) · err_{n-1}^(β), fac_min, fac_max),
//                   α = 0.7/k, β = 0.4/k — the PI controller of Gustafsson (1991), in the form
//                   of Hairer–Wanner II §IV.2 (eq. 2.43c) and DOPRI5; err_{n-1} is the previous
//                   accepted step's error floored at 1e-4 (as in DOPRI5), 1 at the start;
//   rejected step:  h_new = h · max(fac_min, safety · err^(-1/k)) (the I controller of
//                   HNW I §II.4, eq. (4.13)), and the next accepted step may not grow
//                   (fac_max = 1 right after a rejection, HNW I §II.4);
//   failed trial (non-finite values, Newton divergence): h_new = shrink · h, told by the stepper.
// Defaults: safety 0.9, fac_min 0.2, fac_max 5 (HNW I §II.4 recommends 0.8–0.9 and 1.5–5).
//
// First step (HNW I §II.4, "starting step size", p. 169), with the norm above at y0:
//   d0 = ‖y0‖, d1 = ‖f(t0, y0)‖; h0 = 0.01 d0/d1 (1e-6 when d0 or d1 < 1e-5);
//   y1 = y0 + h0 f(t0, y0); d2 = ‖f(t0 + h0, y1) - f(t0, y0)‖ / h0;
//   h1 = (0.01 / max(d1, d2))^(1/(p+1)) (max(1e-6, 1e-3 h0) when max(d1, d2) ≤ 1e-15);
//   h = min(100 h0, h1, t_out - t0, h_max). One extra f evaluation besides f(t0, y0).
#pragma once

#include <limits>
#include <string>

#include "core/ode_system.hpp"
#include "core/params.hpp"
#include "core/solve_stats.hpp"

namespace stiffbench {

struct ControllerOptions {
  double rtol = 1e-6;
  double atol = 1e-10;
  double safety = 0.9;
  double fac_min = 0.2;
  double fac_max = 5.0;
  double h0 = 0.0;  // first step; 0: the heuristic above
  double h_max = std::numeric_limits<double>::infinity();
  long max_steps = 100000;  // trial steps per advance_to call
};

// rtol, atol, max_steps, h0, h_max: the parameters every adaptive method takes.
std::vector<ParamSpec> controller_param_specs();
ControllerOptions read_controller_options(const Params& p);

// Weighted RMS norm of e with scale atol + rtol·max(|y0_i|, |y1_i|).
double wrms_norm(CVecRef e, CVecRef y0, CVecRef y1, double rtol, double atol);

class StepController {
 public:
  StepController() = default;
  // k: the error estimate is O(h^k) (embedded order + 1 for an embedded pair).
  StepController(ControllerOptions opt, int k);

  const ControllerOptions& options() const { return opt_; }
  void reset();
  double norm(CVecRef e, CVecRef y0, CVecRef y1) const {
    return wrms_norm(e, y0, y1, opt_.rtol, opt_.atol);
  }
  // After a trial step of size h with error norm err: true to accept; *h_next is the next step.
  bool judge(double err, double h, double* h_next);

  // The starting step of HNW I §II.4 for a method of order p; f0 = f(t0, y0); y1 and f1 are
  // work vectors of the system's size. `span` = t_out - t0 bounds the result.
  double initial_step(const OdeSystem& sys, double t0, CVecRef y0, CVecRef f0, int p, double span,
                      Vec& y1, Vec& f1) const;

 private:
  ControllerOptions opt_;
  double alpha_ = 0.0, beta_ = 0.0, inv_k_ = 0.0;
  double err_prev_ = 1.0;
  bool after_reject_ = false;
};

// Outcome of one trial step: its error norm, or a failure with the factor to shrink h by.
struct TrialResult {
  double err = 0.0;
  double shrink = 0.0;  // > 0: the trial failed (e.g. Newton diverged); retry with shrink·h
};

// Counters of an adaptive run, cumulative since reset().
struct AdaptiveCounts {
  long accepted = 0;
  long rejected = 0;
};

// The smallest usable step at t: a step h <= 10·u·|t|, u = ε/2 the unit round-off, changes t in
// its last few bits only, so the method can no longer resolve the solution (a finite-time
// singularity, a state outside where the model is defined, a tolerance below round-off). It is
// the test of Hairer's codes DOPRI5 and RADAU5 (0.1·|h| <= |t|·UROUND, UROUND ≈ u), which end
// such a run with "step size too small". No floor at t = 0, as there: near t = 0 every h > 0
// still moves t exactly (a problem may have time scales far below 1), and a step that keeps
// failing there shrinks geometrically until it underflows to 0, which the test catches, or
// until max_steps trials.
inline double step_too_small_limit(double t) {
  return 10.0 * (0.5 * std::numeric_limits<double>::epsilon()) * std::abs(t);
}

// "step size too small: h = ... <= 10·u·|t| = ... at t = ...; largest state component
// y[i] = ..." (y: the state at t).
std::string step_too_small_message(double t, double h, CVecRef y);

// Advances from t to exactly t_out: the step that would pass t_out (or end a few ulps before it)
// is shortened (stretched) to end on it (no interpolation). trial(t, h) -> TrialResult computes a
// candidate step without committing it; commit(t, h) makes the candidate the new state. h is the
// proposed next step on entry and on exit (a step shortened to land on t_out does not shrink the
// proposal for the next call). y is the state at t (what commit writes; read only for the
// message below). Fails with solver_error (message set) after opt.max_steps trials in this call,
// and with step_size_too_small (message naming t, h and y's largest component) when a step falls
// to 10·u·|t| or below (step_too_small_limit).
template <class Trial, class Commit>
Status advance_adaptive(StepController& ctrl, double& t, double t_out, double& h, CVecRef y,
                        AdaptiveCounts& counts, std::string& message, Trial&& trial,
                        Commit&& commit) {
  const ControllerOptions& opt = ctrl.options();
  long trials = 0;
  while (t < t_out) {
    if (trials++ >= opt.max_steps) {
      message = "adaptive: more than max_steps = " + std::to_string(opt.max_steps) +
                " trial steps before t = " + std::to_string(t_out);
      return Status::solver_error;
    }
    double h_try = std::min(h, opt.h_max);
    // A step that would end a few ulps short of t_out lands on it: otherwise rounding in t (e.g.
    // steps of exactly h_max) leaves a last step of a few ulps, which the test below rejects as
    // too small.
    const bool last = t + h_try >= t_out - 64.0 * std::numeric_limits<double>::epsilon() *
                                               std::max(1.0, std::abs(t_out));
    if (last) h_try = t_out - t;
    if (!(h_try > step_too_small_limit(t))) {
      message = step_too_small_message(t, h_try, y);
      return Status::step_size_too_small;
    }
    const TrialResult r = trial(t, h_try);
    if (r.shrink > 0.0) {
      ++counts.rejected;
      h = r.shrink * h_try;
      continue;
    }
    double h_next = 0.0;
    if (ctrl.judge(r.err, h_try, &h_next)) {
      commit(t, h_try);
      ++counts.accepted;
      t = last ? t_out : t + h_try;
      h = last ? std::max(h_next, h) : h_next;
    } else {
      ++counts.rejected;
      h = h_next;
    }
  }
  return Status::ok;
}

}  // namespace stiffbench

// The fixed-step driver: owns the time loop, calls an observer at output times, detects
// blow-up. Steppers take one step; the driver decides where steps go (docs/design.md).
//
// A run over [t0, t_end] with requested step h takes N = max(1, round((t_end - t0)/h)) steps of
// exactly (t_end - t0)/N, so every run ends exactly at t_end and error-vs-h tables report the
// step actually used. Step k ends at t0 + k·h (computed, not accumulated).
#pragma once

#include <functional>
#include <vector>

#include "core/integrator.hpp"
#include "core/run_control.hpp"

namespace stiffbench {

using Observer = std::function<void(double t, CVecRef y)>;

struct FixedStepOptions {
  double t_end = 1.0;
  double h = 0.1;
  // Number of output intervals for the observer: it is called at t0 and then at the steps
  // nearest to each of `outputs` equally spaced times (every step if outputs >= N; 0 means
  // only t0 and t_end).
  long outputs = 0;
  // The run ends with status `unstable` when the state is not finite or its max-norm exceeds
  // blowup_factor × max(1, ‖y0‖∞).
  double blowup_factor = 1e10;
  // Refuse runs longer than this many steps (a typo in h should not hang a sweep).
  long max_steps = 2'000'000'000;
};

struct RunResult {
  SolveStats stats;
  double t = 0.0;    // time reached (t_end when status is ok)
  Vec y;             // state at t
  double h = 0.0;    // the step actually used, (t_end - t0)/N
  long n_steps = 0;  // N
};

// Number of steps the driver takes; BadInput for h <= 0, t_end <= t0 or too many steps.
long fixed_step_count(double t0, double t_end, double h, long max_steps);

// Runs `integ` on `sys` from its initial state. Evaluation counts are the system's counters
// over this run; wall time covers the whole loop (observer included).
RunResult run_fixed_step(const OdeSystem& sys, Integrator& integ, const FixedStepOptions& opt,
                         const Observer& observer = {});

// Same, starting from (t0, y0) instead of the system's initial condition.
RunResult run_fixed_step_from(const OdeSystem& sys, Integrator& integ, double t0, CVecRef y0,
                              const FixedStepOptions& opt, const Observer& observer = {});

struct AdaptiveOptions {
  double t_end = 1.0;
  long outputs = 0;  // observer at t0 and at `outputs` equally spaced times (0: only t_end)
  // When non-empty: the output times instead of `outputs` equally spaced ones. They must be
  // finite, strictly increasing, after t0 and not after t_end (BadInput otherwise). The
  // integrator stops exactly at each (advance_to: no interpolation); the observer is called at
  // t0, at each of them and at t_end when it is not the last of them.
  std::vector<double> times = {};
};

// Runs an adaptive integrator from the system's initial state to t_end, stopping at the output
// times. Status and library counters come from the integrator; f evaluations from the system.
RunResult run_adaptive(const OdeSystem& sys, Integrator& integ, const AdaptiveOptions& opt,
                       const Observer& observer = {});

// Admissible set: a model that declares non-negative components
// (OdeSystem::nonnegative_components, e.g. concentrations) has the state checked at every output
// time — each output step of run_fixed_step* (the last one at least), each output stop of
// run_adaptive. A listed component below -bound ends the run with Status::invalid_state and a
// message naming the component, its value, t and the bound. The bound is the integrator's
// absolute tolerance in an adaptive run (Integrator::absolute_tolerance(), the method's `atol`:
// the error the run was asked to keep, so a value further below 0 is not a small error of a
// valid solution), and 1e-8·max(1, ‖y‖∞) of the state at that time otherwise (a fixed-step run,
// atol = 0, or a method without one): far above round-off, far below a concentration that
// matters. Like unstable, this is a numerical outcome of the method, not a fault.
//
// Faults inside a run: an exception other than BadInput thrown by the model or the
// integrator during run_fixed_step* or run_adaptive (library references included: their
// callbacks pass it across the C library) ends that run with Status::error and the exception's
// message (the state is the last one reached) instead of ending the study. NaN or Inf in the
// state ends it with Status::unstable. A run past its row's wall-clock limit ends with
// Status::timeout; an interruption (request_interrupt) propagates as Interrupted
// (core/run_control.hpp: every run is inside a RowClock, and both are polled at each f
// evaluation and each step). This counts the runs that ended with error or timeout in this
// process; the command line exits with kExitRowsFailed (3) when it is not zero.
long fault_count();
// A row that stopped at its wall-clock limit outside run_* (one method's region or analysis,
// whose rows make no run): counted like a run that ended with status timeout.
void count_row_timeout();

// Timeouts on this thread while an ExpectedTimeouts lives are an outcome the caller planned for
// (`recommend` gives each setting a share of its budget and reports a setting cut short as
// dropped): the run still ends with Status::timeout and its message, but fault_count() does not
// count it, so the command line does not exit 3 for it. Errors are still counted.
class ExpectedTimeouts {
 public:
  ExpectedTimeouts();
  ~ExpectedTimeouts();
  ExpectedTimeouts(const ExpectedTimeouts&) = delete;
  ExpectedTimeouts& operator=(const ExpectedTimeouts&) = delete;

 private:
  bool previous_ = false;
};

}  // namespace stiffbench

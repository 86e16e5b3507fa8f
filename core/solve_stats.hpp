// One statistics record for every integrator, hand-written or library, and one printer.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace stiffbench {

// error: the model or the integrator threw during the run (a fault, not a numerical outcome);
// the driver ends that run with this status and the exception's message (core/driver.hpp).
// timeout: the row passed its wall-clock limit (--max-wall, core/run_control.hpp).
// step_size_too_small: an adaptive method's step fell below 10·u·|t| (u the unit round-off), so
// t + h no longer differs from t by a usable amount (integrators/adaptive/controller.hpp).
// invalid_state: the state left the model's admissible set at an output time, e.g. a
// concentration below minus the run's absolute tolerance (core/driver.hpp).
enum class Status {
  ok,
  unstable,
  newton_failed,
  solver_error,
  error,
  timeout,
  step_size_too_small,
  invalid_state
};

std::string to_string(Status s);

struct SolveStats {
  long steps = 0;
  long error_test_failures = 0;  // rejected steps: the error test failed (adaptive runs)
  long f_evals = 0;              // counted at the system boundary (rhs and acceleration calls)
  long jac_evals = 0;  // analytic Jacobian evaluations (finite-difference ones count as f_evals)
  // linear_setups, lin_solves and newton_iters are kNotReported (-1) for a library that does
  // the work but keeps no count the testbed can read (GSL's implicit steppers): the CSVs leave
  // such a value empty, the tables say "not reported", never 0.
  long linear_setups = 0;  // matrix assemblies / factorizations (Krylov: preconditioner set-ups)
  long lin_solves = 0;
  long newton_iters = 0;
  long newton_conv_failures = 0;  // Newton solves that did not converge (the step was retried
                                  // or the run ended with newton_failed)
  long linear_iters = 0;          // Krylov iterations
  // Calls of the explicit and of the implicit part of an additive split (IMEX, splitting and
  // multirate methods on a split model); each is also one of f_evals. 0 for the other methods.
  long fe_evals = 0;
  long fi_evals = 0;
  static constexpr long kNotReported = -1;
  // A counter's text: its value, or "" when it is kNotReported (any negative value): for CSVs.
  static std::string count_text(long v);
  // The same for tables: "not reported" in place of "".
  static std::string count_shown(const std::string& text);

  // The library's own count of f evaluations (references only; -1 when not reported). It can
  // differ from f_evals, which the testbed counts at the system boundary: see the reference
  // integrators' headers for why.
  long library_f_evals = -1;
  double wall_s = 0.0;
  Status status = Status::ok;
  std::string message;         // why a run did not end ok (empty otherwise)
  std::string library_report;  // a library's own statistics printout (references), or empty

  // The solver counters every study's CSV carries beside f_evals, jac_evals and lin_solves, in
  // this order: newton_iters, newton_conv_failures, error_test_failures (rejected steps),
  // linear_setups (matrix assemblies / factorizations), linear_iters (Krylov iterations),
  // fe_evals and fi_evals (calls of the split's explicit and implicit parts). The names are the
  // columns' names (a contract, docs/formats.md).
  static std::vector<std::string> counter_names();
  std::vector<std::string> counter_values() const;

  // Field names and values in a fixed order, shared by the table and CSV printers.
  static std::vector<std::string> field_names();
  std::vector<std::string> field_values() const;
};

// "  steps          1000" ... one line per field.
void print_stats_table(std::ostream& os, const SolveStats& s);
// Header line and one row, comma separated, in field_names() order.
void print_stats_csv_header(std::ostream& os);
void print_stats_csv_row(std::ostream& os, const SolveStats& s);

}  // namespace stiffbench

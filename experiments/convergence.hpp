// Global- and local-error studies over a ladder of step sizes h_k = h / refine^k.
//
// Global error: max-norm of y_N - y_ref(t_end) after a fixed-step run to t_end.
// Local error: max-norm after ONE step of size h_k from the model's initial state (a fresh
// reset, so history methods take their start-up step), against y_ref(t0 + h_k).
// The reference is the exact solution (`exact`, the default where the model has one) or a run
// of `reference_method` with step (finest h)/16.
// observed_order between consecutive rows of one integrator is log(e_k/e_{k+1})/log(h_k/h_{k+1})
// using the steps actually taken; a global error should give the method's order p, a local
// error p + 1.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "experiments/output.hpp"

namespace stiffbench {

struct ConvergenceSpec {
  std::string model;
  Params params;
  std::vector<std::string> integrators;
  double t_end = 1.0;
  // Coarsest step; NaN: the model's suggested step (SuggestedStep), an error if it has none.
  double h = 0.1;
  int levels = 5;
  double refine = 2.0;
  std::string reference = "auto";  // auto | exact | METHOD

  void validate() const;  // BadInput naming the bad flag
  nlohmann::json to_json() const;
};

struct ConvergenceRow {
  std::string model, integrator;
  int order = 0;
  double h = 0;  // actual step
  long steps = 0;
  double error = 0;
  std::optional<double> observed_order;
  SolveStats stats;
};

struct ConvergenceResult {
  std::vector<ConvergenceRow> rows;
  std::string reference_description;  // "exact" or "rk4 with h = ..."
  double h = 0;                       // the coarsest step requested (spec.h, or the suggested step)
  std::string h_source;               // "--h" or "suggested step: <the model's rule>"
};

// Progress lines go to `progress` when non-null.
ConvergenceResult run_convergence(const ConvergenceSpec& spec, std::ostream* progress);
ConvergenceResult run_local_error(const ConvergenceSpec& spec, std::ostream* progress);

// Least-squares slope of log(error) against log(h) over the last `points` ok rows of one
// integrator (the asymptotic range); empty when fewer than two usable rows.
std::optional<double> fitted_order(const std::vector<ConvergenceRow>& rows,
                                   const std::string& integrator, int points = 3);
// Last observed order of one integrator.
std::optional<double> last_observed_order(const std::vector<ConvergenceRow>& rows,
                                          const std::string& integrator);

Table convergence_table(const ConvergenceResult& r);  // the convergence.csv contract
Table local_error_table(const ConvergenceResult& r);  // the local_error.csv contract

// Writes DIR/NAME.csv, DIR/NAME.md and DIR/NAME.json (NAME = convergence or local_error);
// `local` selects the local-error expectation (order + 1) in the Markdown summary.
void write_convergence_outputs(const std::string& dir, const std::string& name,
                               const ConvergenceSpec& spec, const ConvergenceResult& r, bool local);

}  // namespace stiffbench

// Work-precision: fixed-step integrators over a ladder of step sizes h_k = h/refine^k and
// adaptive ones (the library references) over a ladder of tolerances rtol_k = rtol_max/10^k,
// atol_k = atol_factor·rtol_k, all on one set of axes. Each row: the max-norm error at t_end
// against the reference, the mescd score of the IVP test set
//   mescd = -log10 ‖ |y - y_ref| / (atol/rtol + |y_ref|) ‖∞   (ratio atol/rtol = atol_factor),
// the counters of SolveStats (f_evals, jac_evals, lin_solves, steps and SolveStats::counter_names),
// and the wall time over repeated runs: its median, minimum and a bootstrap 95% interval of the
// median (see "Timing with spread" below).
// The reference and its check: see "The reference" below.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"
#include "experiments/support/reference.hpp"
#include "experiments/support/step_study.hpp"
#include "experiments/support/timed_settings.hpp"
#include "experiments/support/timing.hpp"

namespace stiffbench {

// The step ladder and reference are StepStudySpec's (experiments/support/step_study.hpp) with
// other defaults: t_end = 0 (the model's literature end time); h = 0, the coarsest step: the
// model's suggested step, else (t_end - t0)/16000. Fixed steps on stiff problems are pre-asymptotic
// for a long way (bdf2 on HIRES: the final-time error crosses zero near h = 0.04, so a ladder
// through it is not monotone), so the default starts fine; choose --h for your problem.
// 4 levels; the reference (default cvode_bdf) at rtol 1e-14, atol 1e-16.
struct WorkPrecisionSpec : StepStudySpec {
  WorkPrecisionSpec();
  // rtol from 1e-5 to 1e-10 by default. Looser tolerances are pre-asymptotic for some codes:
  // on HIRES arkode_dirk at rtol 1e-4 took more f evaluations (26503) than at 1e-5 (21962) for
  // a larger error (6.1e-8 vs 4.9e-8), and gsl_bsimp's error rose from 1e-3 to 1e-4.
  int tol_levels = 6;
  double rtol_max = 1e-5;
  double atol_factor = 1e-3;
  // Timing with spread: at most `repeats` runs per point (see kRepeatLongRun, kRepeatBudget),
  // in rounds, each round every point still repeating in an order shuffled with `seed`.
  int repeats = 5;
  unsigned long seed = 1;

  nlohmann::json to_json() const;
  // The most runs per point (`repeats`).
  int max_runs() const { return repeats; }
  // The options of the study registry (work_precision_study_kind) read into the spec.
  void read_options(const Params& options);
  // validate_step_study, and a --reference that is also one of the integrators is BadInput
  // (see "The reference" below).
  void validate() const;
};

// --- The reference ------------------------------------------------------------------------
// `reference` (--reference) is
//  - `auto` (default): the exact solution where the model has one; else the model's published
//    solution when it has one at t_end and its stated accuracy is below the numerical
//    reference's estimated error (below); else the numerical reference, cvode_bdf;
//  - `exact`: the exact solution (BadInput without one);
//  - `published`: the model's published solution at t_end (BadInput without one there);
//  - an integrator (a name or a method file): the numerical reference is that method.
// The numerical reference R is reference_at_end (experiments/support/reference.hpp): an adaptive
// method at --reference-rtol/--reference-atol (default 1e-14, 1e-16), a fixed-step one at
// (finest h)/16. Its accuracy is estimated as convergence estimates its reference's: a second
// run R2, tighter by kReferenceTightening (rtol/10 and atol/10; half the step), and
// ‖R − R2‖∞. Where the model has a published solution P at t_end (ProblemMetadata, the IVP test
// set's), R is also checked against it: ‖R − P‖∞ is recorded beside P's stated accuracy
// (published_accuracy). With `auto`/`published` R is run only as that check (a failed run is
// recorded, not fatal). The reference's estimated error, the floor of the study, is 0 for the
// exact solution, P's stated accuracy when P is the reference, and otherwise the larger of
// ‖R − R2‖∞ and ‖R − P‖∞ (empty when neither is known: the check run failed, no P).
// A row that ended ok with error <= kFloorFactor (10) times that estimate is marked
// `reference_floor` (WorkPrecisionRow::at_reference_floor; the CSV's `flag` column): its error
// measures the reference as much as the method; the plot draws it hollow.
// A --reference method that is also one of the integrators (the same name, or the same method
// file) is BadInput before anything runs: a method measured against itself shares its own
// errors, so its points would show their correlation, not its accuracy. With `auto` the
// numerical reference cvode_bdf may be studied too; that is recorded (method_studied) and said
// in the Markdown.
struct WorkPrecisionReference {
  std::string kind;  // "exact", "published" or "numerical": what the errors are measured against
  std::string description;
  Vec values;                            // the reference state at t_end
  std::optional<double> error_estimate;  // the floor (see above); empty: unknown
  std::string error_source;              // how error_estimate was obtained
  // The numerical reference R (empty description: none ran) and its check run R2.
  std::string numerical_description, check_description;
  std::string numerical_failure, check_failure;  // what a failed run said (auto/published)
  Vec numerical_values;
  std::optional<double> numerical_check;  // ‖R − R2‖∞
  bool method_studied = false;            // R's method is also among the integrators (auto)
  // The model's published solution at t_end, when it has one there.
  bool has_published = false;
  double published_t = 0;
  std::string published_source;
  Vec published_values;
  double published_accuracy = 0;             // published_accuracy(P)
  std::optional<double> published_distance;  // ‖R − P‖∞
};
// The stated accuracy of a published solution (max-norm): its values are given to
// kPublishedDigits significant digits (the IVP test set's reference solutions, computed with
// RADAU at rtol = atol = 1.1e-18 with unit round-off 1.01e-19, Mazzia & Magherini 2008), so
// each component is good to half a unit in its last digit, 0.5·10^(floor(log10|y_i|) − 15),
// plus its rounding to double, 2^-53·|y_i|; the largest over the components.
constexpr int kPublishedDigits = 16;
double published_accuracy(const OdeSystem::PublishedSolution& p);
// The reference of a work-precision study at spec.t_end (the spec resolved: t_end > t0, the
// reference a name); h_fine: the finest step of the fixed-step ladder. BadInput as above.
WorkPrecisionReference work_precision_reference(const StudyInputs& in,
                                                const WorkPrecisionSpec& spec, const OdeSystem& sys,
                                                double h_fine, std::ostream* progress);
// (Timing with spread, the row of a timed setting and run_work_precision_setting:
// experiments/support/timing.hpp and experiments/support/timed_settings.hpp.)

struct WorkPrecisionResult {
  std::vector<WorkPrecisionRow> rows;
  std::string reference_description;  // reference.description
  WorkPrecisionReference reference;
  double t_end = 0;
  double h = 0;          // coarsest step of the fixed-step methods
  std::string h_source;  // where it came from
};

// Runs the study on `in` (its model, parameters and integrators replace the spec's; a
// user-named reference is looked up there). Progress lines go to `progress` when non-null.
WorkPrecisionResult run_work_precision(const StudyInputs& in, const WorkPrecisionSpec& spec,
                                       std::ostream* progress);
// The same on the names the spec gives (resolve_inputs first).
WorkPrecisionResult run_work_precision(const WorkPrecisionSpec& spec, std::ostream* progress);
// The CSV contract: model, integrator, setting, error, f_evals, jac_evals, lin_solves, steps,
// wall_s, status, mescd, the solver counters (SolveStats::counter_names), wall_s_median,
// wall_s_min, wall_s_ci_low, wall_s_ci_high, repeats, then flag (`reference_floor` for a row
// at_reference_floor, else empty) and reference_error (the reference's estimated error, the same
// on every row; empty when unknown).
Table work_precision_table(const WorkPrecisionResult& r);
// Adaptive methods whose error does not follow the tolerance, one Markdown line each: among a
// method's ok rows at rtol settings (3 or more, errors > 0), the least-squares slope of
// log(error) against log(rtol) is below kToleranceResponseMin while the tightest setting's error
// is more than 100 times its rtol. Its step control then does not see its error on this problem
// (an embedded estimate that vanishes, e.g. ros3p on a linear autonomous system, or is filtered
// away), so its points are not a work-precision curve, although every run ends ok.
constexpr double kToleranceResponseMin = 0.3;
std::vector<std::string> tolerance_response_notes(const WorkPrecisionResult& r);
void write_work_precision_outputs(const std::string& dir, const WorkPrecisionSpec& spec,
                                  const WorkPrecisionResult& r);

// What `stiffbench work-precision` does, for a program that links the library: checks DIR (it
// can be written; it holds no work_precision.* of a different spec: check_study_output with
// spec.to_json() and force_output()), runs
// the study, writes DIR/work_precision.{csv,md,json} and draws DIR/work_precision.png when
// gnuplot is installed.
WorkPrecisionResult work_precision_study(const WorkPrecisionSpec& spec, const std::string& dir,
                                         std::ostream* progress, std::ostream& err,
                                         const PlotOptions& plot = {});
// The one call on resolved inputs (a program's objects: resolve_inputs(StudyTarget{.objects =
// ...})): the pipeline of experiments/framework/study.hpp.
WorkPrecisionResult work_precision_study(const StudyInputs& in, WorkPrecisionSpec spec,
                                         const std::filesystem::path& dir,
                                         const StudyContext& ctx = {});
const WorkPrecisionResult& work_precision_result(const StudyJob& job);

}  // namespace stiffbench

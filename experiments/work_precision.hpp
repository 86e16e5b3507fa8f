// Work-precision: fixed-step integrators over a ladder of step sizes h_k = h/refine^k and
// adaptive ones (the library references) over a ladder of tolerances rtol_k = rtol_max/10^k,
// atol_k = atol_factor·rtol_k, all on one set of axes. Each row: the max-norm error at t_end
// against the reference, the mescd score of the IVP test set
//   mescd = -log10 ‖ |y - y_ref| / (atol/rtol + |y_ref|) ‖∞   (ratio atol/rtol = atol_factor),
// the counters of SolveStats, and the wall time as the minimum over `repeats` runs.
// The reference is the exact solution where the model has one, otherwise a run of
// `reference` (default cvode_bdf at rtol 1e-14, atol 1e-16 — on HIRES it agrees with the IVP
// test set's published solution to ~1e-13, while rtol 1e-12 is off by ~1e-11; a fixed-step
// reference method runs at (finest h)/16).
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "experiments/catalog.hpp"
#include "experiments/convergence.hpp"
#include "experiments/output.hpp"
#include "experiments/plotting.hpp"

namespace stiffbench {

// The step ladder and reference are StepStudySpec's (experiments/convergence.hpp) with other
// defaults: t_end = 0 (the model's literature end time); h = 0, the coarsest step: the model's
// suggested step, else (t_end - t0)/16000. Fixed steps on stiff problems are pre-asymptotic
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
  int repeats = 3;

  nlohmann::json to_json() const;
};

struct WorkPrecisionRow {
  std::string model, integrator, setting;
  double error = 0, mescd = 0;
  SolveStats stats;
};

struct WorkPrecisionResult {
  std::vector<WorkPrecisionRow> rows;
  std::string reference_description;
  double t_end = 0;
  double h = 0;          // coarsest step of the fixed-step methods
  std::string h_source;  // where it came from
};

WorkPrecisionResult run_work_precision(const WorkPrecisionSpec& spec, std::ostream* progress);
// The same on a user's objects (see run_convergence with StudyObjects).
WorkPrecisionResult run_work_precision(WorkPrecisionSpec spec, const StudyObjects& objects,
                                       std::ostream* progress);
WorkPrecisionResult run_work_precision(WorkPrecisionSpec spec, const SystemFactory& system,
                                       std::ostream* progress);
Table work_precision_table(const WorkPrecisionResult& r);
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
// The one call on a user's objects (the pipeline of experiments/study.hpp).
WorkPrecisionResult work_precision_study(WorkPrecisionSpec spec, const StudyObjects& objects,
                                         const std::filesystem::path& dir,
                                         const StudyContext& ctx = {});
const WorkPrecisionResult& work_precision_result(const StudyJob& job);

}  // namespace stiffbench

// Global- and local-error studies over a ladder of step sizes h_k = h / refine^k.
//
// Global error: max-norm of y_N - y_ref(t_end) after a fixed-step run to t_end.
// Local error: max-norm after ONE step of size h_k from the model's initial state (a fresh
// reset, so history methods take their start-up step), against y_ref(t0 + h_k).
// The reference (--reference) is
//  - `exact`: the model's exact solution; the default (`auto`) where the model has one;
//  - an adaptive integrator (cvode_bdf, cvode_adams, arkode_*, gsl_*: any whose
//    supports_adaptive() is true; those with a fixed-step mode too run adaptively here), run
//    from the initial state with rtol = --reference-rtol (default 1e-12) and atol =
//    --reference-atol (default rtol/100), stopping exactly (no interpolation) at t_end, or at
//    every t0 + h_k for the local study; the other integrator parameters are the user's --param
//    values where the integrator declares them, else its defaults;
//  - a fixed-step integrator (e.g. rk4), run with step (finest h)/16.
// A model without an exact solution has no default: `auto` there is BadInput asking for
// --reference (as before adaptive references existed). The tolerance flags are BadInput with an
// exact or a fixed-step reference, where they would silently do nothing.
//
// Cache: with `cache_dir` set (the commands pass --out), a non-exact reference is stored in
// DIR/reference/<16 hex digits>.csv: a comment line with the key (JSON: cache format,
// stiffbench version and git revision, model and its parameters with defaults filled in, a hash
// of the initial state, a fingerprint of the right-hand side (f at three documented states and
// the analytic Jacobian where there is one, so a changed system never reuses a stale reference),
// reference integrator and its effective parameters including rtol/atol or the fixed step, t0 and
// the reference times), a readable comment line, then `t,y0,y1,...` rows at the reference times
// (t_end; or t0 + h_k for the local study) printed with %.17g. The file name is the 64-bit FNV-1a
// hash of the key; a file is reused only when its key line matches exactly and its rows are
// complete, otherwise the reference is recomputed and the file rewritten (atomically). The
// integrators under study and the h ladder (except through a fixed reference's step or the local
// study's times) are not in the key: adding an integrator reuses the reference. observed_order
// between consecutive rows of one integrator is log(e_k/e_{k+1})/log(h_k/h_{k+1}) using the steps
// actually taken; a global error should give the method's order p, a local error p + 1.
//
// Floors. Every row is checked against two floors below which its error says nothing about the
// method:
//  - the round-off floor, chosen by --floor:
//    `auto` (the default): measured per integrator. At its finest level that ran ok the run is
//      repeated twice from y0 with every nonzero component scaled by 1 ± kFloorPerturbation
//      (2^-30; the signs s_i = ±1 from a fixed-seed generator, so runs are reproducible; zero
//      components stay exact, except when y0 = 0, whose components move by ±2^-30): y₊ from 1 +
//      s_i·2^-30, y₋ from 1 − s_i·2^-30. Their mean minus the unperturbed result y, d = (y₊ + y₋)/2
//      − y, cancels the first-order response to the perturbation (the second-order one, about 2^-60
//      relative, is far below the rounding), so it is rounding only: three runs whose rounding
//      differs (the perturbation moves every increment h·k by many ulps of y, which a perturbation
//      of a few ulps of y0 does not: both runs would round y + h·k alike). The floor is 2‖d‖∞
//      (about 2σ, σ the rounding error of a run, when the three are independent), at least u·‖y‖∞.
//      A level with N steps gets the floor scaled by √(N/N_f), N_f the steps of the measurement (a
//      random walk of rounding errors; rk4 on the oscillator grows faster, about N^0.8, so coarser
//      levels get a larger floor than their rounding); the local error's one step has the measured
//      floor at every h. Source `perturbed`; `model` when there is nothing to measure (no level ran
//      ok or a rerun failed).
//    `model`: the bound N·u·s for a global error after N steps and u·s for a local error (one
//      step), with u = 2^-53 the unit round-off and s = max(1, ‖y0‖∞, ‖y_ref‖∞) the solution's
//      size (y_ref at t_end, or at t0 + h for the local error). Every row carries it
//      (roundoff_floor) whatever --floor says; it is an upper bound of the accumulated rounding
//      of a stable run, far above it on a damped (stiff) problem.
//    a number: that absolute error for every row (source `given`).
//  - for a numerical reference, the reference's own accuracy: ‖y_ref − y_ref2‖∞ at the same
//    time, where y_ref2 is a second reference run, tighter by a factor 10 (rtol/10 and atol/10
//    for an adaptive reference; half the step for a fixed-step one); it is cached like the first
//    (another key). An exact reference has no such floor (0).
// A row whose error is at most kFloorFactor (10) times either floor has status `floor` (its error
// stays in the table) and is left out of order fits; except, for a measured floor, a row above it
// (kFloorKeepFactor = 1; the floor is about 2σ) whose pairwise order with the coarser usable
// level is within kOrderTolerance (0.1) of the expected slope: its error still falls at the
// method's order, so rounding does not set it (checked level by level from the coarse end). With a
// measured floor F ≈ 2σ (σ the rounding error), an error 10 F = 20σ carries a relative noise of 5%,
// which moves a pairwise order by about 0.07 for refine 2.
//
// Orders (fit_order): over the rows of one integrator, the asymptotic window is the longest run
// of consecutive levels that ran ok, are above both floors, and whose pairwise observed orders
// all lie within kOrderAgreement (0.2) of each other (max − min); among equally long runs the
// finest. The fitted order is the least-squares slope of log(error) against log(h) over the
// window, with its standard error; with fewer than three levels in the window there is no fit
// and the reason says what to change. A fit more than kOrderTolerance from the expected slope, or
// with finer levels above the floors that leave the window, gets a reason read from the pairwise
// orders (docs/commands/convergence.md lists the cases): orders still moving towards the expected
// slope at the window's finest level, or a finest pair at it beyond a window that is not, are
// pre-asymptotic, never an order reduction or a higher order. For a local error the fitted slope
// is order + 1. A reason names what removed levels (the round-off floor and how it was found, the
// reference's accuracy, failed runs, pre-asymptotic or unsettled orders) and advises only a change
// that can alter the result (no_fit_reason).
//
// Ladders (--ladder): `common` runs every integrator on h_k = h/refine^k. `per-method` gives
// each integrator its own coarsest step h0 (then h0/refine^k, same levels and refine), found by
// a probe of at most kProbeRuns cheap runs (p: the classical order, p + 1 for the local error).
// Stage 1, the coarsest step allowed: starting at h, a run whose error is not finite or above
// the target 1e-2·s divides h by 4, one at its floor multiplies h by 4, otherwise h moves to the
// step e ∝ h^p predicts for the target (log-log interpolation once bracketed), until an error is
// within a factor 3 below the target; h_top is that step (or the prediction from the last usable
// probe, never at or past a probe that failed or overshot). Stage 2: the ladder moves down, by at
// most its own length (h0 ≥ h_top·refine^-(levels-1)), until its predicted finest error is about
// kLadderFloorMargin (100) times the larger floor, checked by one or two runs at that finest step
// (within a factor 3): the most asymptotic levels that stay well above the floors. With --floor
// auto the round-off floor of stage 2 is measured once, by the two perturbed reruns at the
// finest step of the coarsest allowed ladder (h_top·refine^-(levels-1)), and grows in proportion
// to the number of steps below that step (a bound for the accumulated rounding); the study then
// measures it again at the ladder's own finest level. h0 stays
// within [h/64, 16·h], for the global error at most (t_end − t0)/4 and with its finest level
// within the driver's step limit. A fixed-step reference runs at (finest h of the common
// ladder)/16 in both modes (for the local error at most (t − t0)/16 at each reference time t).
//
// The code of these rules that work-precision and recommend share lives in experiments/support/:
// the spec and options (step_study), the reference and its cache (reference), the order fit
// (order_fit) and the ladder probe's stages (step_ladder).
#pragma once

#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"
#include "experiments/support/order_fit.hpp"
#include "experiments/support/reference.hpp"
#include "experiments/support/step_ladder.hpp"
#include "experiments/support/step_study.hpp"

namespace stiffbench {

struct ConvergenceSpec : StepStudySpec {
  static constexpr double kDefaultReferenceRtol = kStepReferenceRtol;
  // "common" (every integrator on h/refine^k) or "per-method" (a probe per integrator).
  std::string ladder = "common";
  static constexpr double kReferenceAtolDivisor = kStepReferenceAtolDivisor;  // atol = rtol/100
  // Folder holding the reference cache (DIR/reference/); empty: no cache. Not part of the spec's
  // JSON (it is where the outputs go).
  std::string cache_dir;
  // The round-off floor (--floor): "auto" (measured per integrator by perturbed reruns), "model"
  // (N·u·s per row) or a positive number (that absolute error for every row). See the top.
  std::string floor = "auto";
  // The number of --floor VALUE; empty for auto and model. BadInput naming --floor otherwise.
  std::optional<double> given_floor() const;

  void validate() const;  // BadInput naming the bad flag
  nlohmann::json to_json() const;
};

// The floor check's constants (see the top of this file).
// (kUnitRoundoff, kFloorFactor: experiments/support/step_study.hpp; kOrderAgreement,
// kOrderTolerance, kOrderReductionSpread, kLadderFloorMargin: experiments/support/order_fit.hpp;
// kReferenceTightening: experiments/support/reference.hpp; kLadderTop, kProbeRuns:
// experiments/support/step_ladder.hpp.)
// --floor auto (the top of this file): the relative perturbation of y0 and its signs' seed, and
// the factor from the second difference to the floor.
constexpr double kFloorPerturbation = 0x1p-30;
constexpr unsigned long long kFloorSeed = 0x9e3779b97f4a7c15ULL;
constexpr double kFloorSecondDifferenceFactor = 2;
// A row above kFloorKeepFactor and within kFloorFactor times a measured floor stays ok when its
// pairwise order with the coarser usable level is within kOrderTolerance of the expected slope.
constexpr double kFloorKeepFactor = 1;

// The floor measurement of --floor auto: two reruns from y0 scaled by 1 ± kFloorPerturbation
// (perturbed_initial_state with sign +1 and -1). `run(y0')` returns the final state of a run from
// y0', empty when it did not end ok; `y` is the unperturbed run's final state. The floor is
// kFloorSecondDifferenceFactor ‖(y₊ + y₋)/2 − y‖∞, at least u·‖y‖∞; empty when a rerun did not
// end ok. `spreads` receives ‖y₊ − y‖∞, ‖y₋ − y‖∞ and
// ‖(y₊ + y₋)/2 − y‖∞.
std::optional<double> measure_roundoff_floor(
    const Vec& y0, const Vec& y, const std::function<std::optional<Vec>(const Vec&)>& run,
    std::vector<double>* spreads = nullptr);
// y0 with each nonzero component scaled by 1 + sign·s_i·kFloorPerturbation, s_i = ±1 from a
// splitmix64 sequence seeded with kFloorSeed (deterministic; zero components stay exact; when y0
// = 0 every component becomes sign·s_i·kFloorPerturbation).
Vec perturbed_initial_state(const Vec& y0, int sign);

struct ConvergenceRow {
  std::string model, integrator;
  int order = 0;
  double h = 0;    // actual step
  long steps = 0;  // steps taken: N = round(T/h), fewer when the run ended early
  double error = 0;
  std::optional<double> observed_order;
  SolveStats stats;
  double roundoff_floor = 0;   // the model N·u·s (global) or u·s (local), whatever --floor says
  double reference_floor = 0;  // the reference's estimated accuracy (0: exact reference)
  double floor_used = 0;       // the round-off floor the row is checked against (--floor)
  std::string floor_source;    // how it was found: perturbed, model or given
  bool at_floor = false;       // ok and error <= kFloorFactor × floor_used or reference_floor
  // "floor" for a row at a floor, else the run's status.
  std::string status_text() const;
};

// The fit over the asymptotic window of the rows of `integrator` (in ladder order; their
// at_floor and status must be set). `local`: the expected slope is order + 1. `ladder`: the
// ladder that ran ("common" or "per-method"), so that the advice never names the one in use.
// (experiments/support/order_fit.hpp on the integrator's points; the fit's integrator is set).
OrderFit fit_order(const std::vector<ConvergenceRow>& rows, const std::string& integrator,
                   bool local, const std::string& ladder = "common");
// The fit's view of one row.
FitPoint fit_point(const ConvergenceRow& row);

struct ConvergenceResult {
  std::vector<ConvergenceRow> rows;
  std::string
      reference_description;    // "exact", "cvode_bdf adaptive, rtol = ..." or "rk4 with h = ..."
  std::string reference_cache;  // the cache file used or written; empty without a cache
  bool reference_from_cache = false;  // true: read from reference_cache, not recomputed
  double h = 0;                       // the coarsest step requested (spec.h, or the suggested step)
  std::string h_source;               // "--h" or "suggested step: <the model's rule>"
  // The second reference run (empty for an exact reference): its description and, for the
  // global error, the estimated accuracy of the reference at t_end (the largest over the
  // reference times for the local error).
  std::string reference_check_description, reference_check_cache;
  std::optional<double> reference_accuracy;
  std::string ladder = "common";
  // Per-method ladders: each integrator's coarsest step and its probe runs ("h=... error=...").
  struct Ladder {
    std::string integrator;
    double h0 = 0;
    std::vector<std::pair<double, double>> probes;  // (h, error; NaN when the run failed)
    // --floor auto: the round-off floor the probe measured and the step of its reruns (0: none).
    double floor = 0, floor_h = 0;
  };
  std::vector<Ladder> ladders;
  std::vector<OrderFit> fits;  // one per integrator, in run order
  // The round-off floor of each integrator (one per integrator, in run order).
  struct Floor {
    std::string integrator;
    double value = 0;    // the floor at the finest level (a row with N steps: value·√(N/N_f))
    std::string source;  // perturbed, model or given
    double h = 0;        // perturbed: the step of the reruns
    long steps = 0;      // perturbed: their number of steps N_f
    std::vector<double> spreads;  // perturbed: ‖y_m − y‖∞ of each rerun (NaN: it failed)
    std::string note;             // auto that fell back to the model: why
  };
  std::vector<Floor> floors;
  std::string floor_mode = "auto";  // the spec's --floor
};

// Runs the study on `in` (its model, parameters and integrators replace the spec's); the
// reference and its tolerances are the spec's, a user-named reference looked up in `in`.
// Progress lines go to `progress` when non-null.
ConvergenceResult run_convergence(const StudyInputs& in, const ConvergenceSpec& spec,
                                  std::ostream* progress);
ConvergenceResult run_local_error(const StudyInputs& in, const ConvergenceSpec& spec,
                                  std::ostream* progress);
// The same on the names the spec gives (resolve_inputs first).
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
// NAME_orders.csv: integrator,order,analysed_order,fitted_order,fitted_order_se,h_min,h_max,
// levels_used,reason,floor_used,floor_source.
Table orders_table(const ConvergenceResult& r);

// Writes DIR/NAME.csv, DIR/NAME_orders.csv, DIR/NAME.md and DIR/NAME.json (NAME = convergence or
// local_error; its "spec" is spec.to_json(), the step used is h_used with h_source beside it);
// `local` selects the local-error expectation (order + 1) in the Markdown summary.
void write_convergence_outputs(const std::string& dir, const std::string& name,
                               const ConvergenceSpec& spec, const ConvergenceResult& r, bool local);

// The jobs of the study registry hold these results (experiments/framework/study.hpp).
const ConvergenceResult& convergence_result(const StudyJob& job);

// What `stiffbench convergence` / `local-error` do, for a program that links the library: checks
// that DIR can be written and holds no NAME.* of a different spec (check_study_output with
// spec.to_json() and force_output(); the note to `err`), runs the study (progress lines to
// `progress` when non-null; the
// reference cache in DIR unless spec.cache_dir is set), writes DIR/NAME.{csv,md,json} and draws
// DIR/NAME.png when gnuplot is installed (warnings to `err`).
ConvergenceResult convergence_study(ConvergenceSpec spec, const std::string& dir, bool local,
                                    std::ostream* progress, std::ostream& err,
                                    const PlotOptions& plot = {});
// The one call on resolved inputs (a program's objects: resolve_inputs(StudyTarget{.objects =
// ...})): check DIR, run, write, plot, print (ctx.out) — the pipeline of
// experiments/framework/study.hpp with ctx's settings (force, plot format, streams); the
// reference cache in DIR unless spec.cache_dir or ctx.cache_dir is set.
ConvergenceResult convergence_study(const StudyInputs& in, ConvergenceSpec spec,
                                    const std::filesystem::path& dir, bool local,
                                    const StudyContext& ctx = {});

}  // namespace stiffbench

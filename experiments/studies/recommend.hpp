// Recommend: "which integrator, at my tolerance?" (`stiffbench recommend`,
// docs/commands/recommend.md). A quick work-precision sweep over the methods suited to the
// model, within a wall-time budget, and a ranked answer.
//
// Candidates: every registered integrator (and a user's integrator objects) that the model can
// run (check_compatible), kept or dropped by family from the model's capabilities:
//   stiff       the stiffness ratio rho·(t_end - t0) >= kStiffRatio, rho the model's estimate
//               OdeSystem::stiffness at the initial state (no estimate: not stiff unless the
//               model is mechanical with a Jacobian, where spring stiffness is assumed);
//   explicit_rk kept when not stiff (a stiff problem needs h below the explicit stability
//               limit ~ 3/rho);
//   implicit, reference (CVODE, ARKODE, GSL, ...) and imex/splitting kept when stiff or when
//               the model is small (dimension <= kSmallDimension) — on a non-stiff model the
//               explicit pairs are cheaper, but a small model costs little to check;
//   symplectic, graphics kept for mechanical models (the requirements check does the rest).
// t_end: --t-end, else the model's literature end time, else for a mechanical model
// kSceneEndTime (one second of a scene), else BadInput naming --t-end.
// Sweep: an adaptive method at rtol = R·10, R, R/10, R/100 (atol = rtol·kRecommendAtolRatio),
// a fixed-step method at h = h0, h0/4, h0/16, ... (kFixedLevels levels; h0 the model's
// suggested step, else (t_end - t0)/100), each setting timed like a work-precision point
// (run_work_precision_setting). A method stops at its first setting that meets R, at a failed
// adaptive run, at a timeout, or when its share of the budget is spent. Its share is the
// remaining budget (95% of --budget less the time used) divided by the methods still to run,
// and is the row clock's limit of its settings, so a slow setting ends as `timeout`.
// Meets the tolerance: error_rel = ||y - y_ref||_inf / max(1, ||y_ref||_inf) <= R at t_end;
// y_ref is the exact solution, else an adaptive run (reference_at_end, not cached:
// cvode_bdf, or cvode_adams on a model that is not stiff, at rtol = max(1e-14, R·1e-4),
// atol = rtol/100), limited to half the budget.
// Pareto: among the rows that ended ok, a row is on the front for wall time (f evaluations)
// when no other ok row has error_rel <= and cost <= with one of them strictly smaller.
// Answer: the rows that meet R with the smallest median wall time and the smallest f_evals
// (ties: the smaller wall time); per method its cheapest meeting row, ranked by wall time; the
// methods without one, with the reason (unstable, failed, timeout, never reached R, budget).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/support/timed_settings.hpp"

namespace stiffbench {

constexpr double kStiffRatio = 1e3;
constexpr long kSmallDimension = 100;
constexpr int kFixedLevels = 6;
constexpr double kRecommendAtolRatio = 1e-3;  // atol = rtol·this for the adaptive settings
constexpr double kSceneEndTime = 1.0;         // s: a mechanical model without a literature end time

struct RecommendSpec {
  std::string model;
  Params params;
  std::vector<std::string> integrators;  // added to the candidates (labels of the inputs)
  double rtol = 0;
  double t_end = 0;  // 0: the model's literature end time
  double budget_s = 60;
  int timing_repeats = 3;
  unsigned long seed = 1;

  void validate() const;  // BadInput naming the flag
  nlohmann::json to_json() const;
};

struct RecommendCandidate {
  std::string integrator, family;
  bool included = false;
  std::string reason;
};

struct RecommendRow {
  WorkPrecisionRow run;  // integrator, setting, error, stats, wall
  std::string family;
  double error_rel = 0;  // NaN unless ok
  bool meets = false, pareto_wall = false, pareto_f = false;
};

struct RecommendResult {
  std::string model;
  double rtol = 0, budget_s = 0;
  double t_end = 0, h0 = 0, ref_norm = 0;
  std::string h0_source, reference_description, stiffness_note;
  bool stiff = false, mechanical = false;
  long dimension = 0;
  std::vector<RecommendCandidate> candidates;
  std::vector<RecommendRow> rows;
  std::vector<std::pair<std::string, std::string>> dropped;  // method, reason
  std::optional<std::size_t> best_wall, best_f;              // row indices
  std::vector<std::size_t> ranked;  // per method its cheapest meeting row, by wall time
  double total_wall_s = 0;
};

// Runs the sweep on `in` (its model, parameters and integrators replace the spec's; the
// candidates are the registered integrators and `in`'s). Progress lines go to `progress`.
RecommendResult run_recommend(const StudyInputs& in, const RecommendSpec& spec,
                              std::ostream* progress);
// The same on the names the spec gives (resolve_inputs first).
RecommendResult run_recommend(const RecommendSpec& spec, std::ostream* progress);
// Marks pareto_wall and pareto_f of the rows (see the header comment).
void mark_pareto(std::vector<RecommendRow>& rows);
Table recommend_table(const RecommendResult& r);
std::string recommend_markdown(const RecommendResult& r);

// The one call on resolved inputs (a program's objects: resolve_inputs(StudyTarget{.objects =
// ...})): check DIR, run, write recommend.{csv,md,json}, plot, print (ctx.out).
RecommendResult recommend_study(const StudyInputs& in, RecommendSpec spec,
                                const std::filesystem::path& dir, const StudyContext& ctx = {});
const RecommendResult& recommend_result(const StudyJob& job);

}  // namespace stiffbench

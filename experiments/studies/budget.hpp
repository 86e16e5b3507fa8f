// Budget: what a frame of a mechanical scene costs and how much the scene stretches, for each
// method over a grid of configurations (substeps × iterations), at a fixed frame time
// (`stiffbench budget`, docs/commands/budget.md).
//
// Configurations. Every configuration advances the scene by whole frames of length `frame`
// (default 1/60 s) with `substeps` fixed steps per frame, h = frame/substeps. A method that
// declares an integer parameter `iterations` (xpbd, projective_dynamics, or a user's method)
// runs at every pair (substeps, iterations) of the two lists, total_iterations = substeps ×
// iterations per frame; the other methods at every substeps value only. A method that declares a
// parameter `substeps` of its own (xpbd) runs with it set to 1, so that its substeps are the
// driver's steps of h = frame/substeps; one xpbd step of h with its own S substeps is the same
// computation as S steps of h/S with substeps = 1 (each of its substeps predicts, resets λ,
// iterates and updates v from the positions), so the counts in the table are the ones the method
// performed.
//
// Per configuration, from the model's initial state over `frame_count` frames:
//   ms_per_frame   wall time of the frame loop (the integrator's set-up in reset() excluded,
//                  e.g. a prefactorisation) / frame_count, in ms; timed over repeated runs with
//                  the timing of work-precision (experiments/support/timing.hpp: rounds
//                  shuffled with the seed, kRepeatLongRun, kRepeatBudget, timing_spread: median,
//                  minimum, bootstrap 95% interval) and the maximum;
//   strain         for a spring network (OdeSystem::spring_network()): the relative strain
//                  |l - L|/L of every spring with k > 0 and L > 0 (structural, shear and bend
//                  alike); strain_max and strain_rms at the last frame, strain_peak the largest
//                  strain_max over all frames (the initial state included);
//   constraint     for a model with constraints (has_constraints()): constraint_residual() at
//                  the last frame and its maximum over the frames;
//   energy_rel     (E_N - E_0)/D for the model's `energy` invariant, D = max(|E_0|, the largest
//                  kinetic energy ½ vᵀ M v over the frames): a scene that starts at rest near
//                  E = 0 (the cloth) is measured against the energy its motion had, not against
//                  the round-off of E_0; |E_0| is left out of D when the energy's zero is
//                  arbitrary (Invariant::arbitrary_zero: gravity's potential is zero at x = 0);
//   angular_momentum_drift   when the model lists angular momentum invariants (a mass-spring
//                  network without pins, point damping or gravity across the axis): the largest
//                  change |L_c(end) - L_c(0)| over the listed components, relative to |L_c(0)|
//                  unless |L_c(0)| <= kZeroInvariant (then absolute, as in `energy`);
//   status         ok; unstable (non-finite, the driver's blow-up bound, or strain_peak above
//                  max_strain); or the failure the driver reports (newton_failed, error, ...);
//   fits           status ok and ms_per_frame (median) <= frame.
//   strain_error   for a spring network with a reference: |strain_i - strain_i(ref)| over the
//                  springs at the last frame, max and RMS. The reference is the same scene run
//                  with ref_integrator (default rk4) at ref_substeps (default 200) steps per
//                  frame; its run at half as many steps is its check (ref_check, in the JSON and
//                  the Markdown). A scene that does not start at its rest lengths (the cloth's
//                  `perturbation`) keeps some strain that is not error: the strain of the true
//                  motion; strain_error measures each method against it.
// The error of a configuration (Pareto plot, best configuration) is strain_error_max when the
// model has springs and the reference ran ok, else strain_max, else constraint_residual when it
// has constraints, else there is none and the plot is not drawn.
#pragma once

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "core/springs.hpp"
#include "core/types.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"
#include "experiments/support/timing.hpp"

namespace stiffbench {

struct BudgetSpec {
  std::string model;
  Params params;
  std::vector<std::string> integrators;
  double frame = 1.0 / 60.0;  // s
  long frame_count = 10;
  // The grid: substeps per frame (every method) × iterations (methods with `iterations`). The
  // defaults hold the equal-total families 1×20, 2×10, 4×5, 10×2, 20×1 (total 20), 1×10, 2×5,
  // 10×1 and 2×20, 4×10, 20×2 (Macklin et al. 2019).
  std::vector<long> substeps_list = {1, 2, 4, 10, 20};
  std::vector<long> iterations_list = {1, 2, 5, 10, 20};
  int timing_repeats = 3;  // most runs per configuration (experiments/support/timing.hpp)
  unsigned long seed = 1;
  double max_strain = 10.0;  // strain_peak above this is `unstable` (spring networks)
  // Reference of the strain error (spring networks): the same scene run with `ref_integrator`
  // at ref_substeps steps per frame, checked against its own run at ref_substeps/2 (0: none).
  std::string ref_integrator = "rk4";
  long ref_substeps = 200;

  void validate() const;  // BadInput naming the flag
  nlohmann::json to_json() const;
};

// The strain of a spring network at positions x (the first dim × points entries of a state):
// over the springs with k > 0 and L > 0, max and RMS of |l - L|/L; `springs` counts them.
struct StrainStats {
  double max = 0, rms = 0;
  long springs = 0;
};
StrainStats spring_strain(const SpringNetworkView& net, CVecRef x);
// |l - L|/L of every spring with k > 0 and L > 0, in the order of net.springs.
std::vector<double> spring_strains(const SpringNetworkView& net, CVecRef x);

struct BudgetRow {
  std::string integrator;
  long substeps = 0;
  std::optional<long> iterations;  // methods with an `iterations` parameter
  double h = 0;
  TimingSpread ms;  // per frame, in ms (median, min, bootstrap interval)
  double ms_max = 0;
  // Errors (NaN when the model has no springs / constraints, or the run did not end ok).
  double strain_max = 0, strain_rms = 0, strain_peak = 0;
  // |strain_i - strain_i(reference)| over the springs at the last frame (NaN without a reference).
  double strain_error_max = 0, strain_error_rms = 0;
  double constraint = 0, constraint_peak = 0;
  double energy_rel = 0;                // NaN without an energy invariant
  std::optional<double> angular_drift;  // models with angular momentum invariants
  bool fits = false;
  SolveStats stats;  // the first run's status, message and counters

  std::optional<long> total_iterations() const {
    if (!iterations) return std::nullopt;
    return substeps * *iterations;
  }
  // strain_error_max, else strain_max, else constraint, else NaN (see the header comment).
  double error() const;
};

struct BudgetResult {
  std::string model;
  double frame = 0;
  long frame_count = 0;
  // "strain_error_max", "strain_max", "constraint_residual" or "" (none)
  std::string error_measure;
  double initial_strain_max = 0;  // of the initial state (spring networks)
  // The reference's strains at the last frame (per spring with k > 0 and L > 0; empty: none) and
  // its self-check: max |strain_i(ref_substeps) - strain_i(ref_substeps/2)|, an upper bound of
  // the reference's own strain error for a method of order >= 1.
  std::vector<double> ref_strains;
  double ref_check = 0;
  std::string ref_note;  // how the reference was made, or why there is none
  std::string energy_scale_note;
  std::vector<BudgetRow> rows;
};

// Runs the grid of every integrator of `in` on its model (a mechanical one), after its
// reference (spec.ref_integrator, looked up in `in` too); the spec's model, params and
// integrators are `in`'s. Progress lines go to `progress` when non-null.
BudgetResult run_budget(const StudyInputs& in, const BudgetSpec& spec, std::ostream* progress);
// The same on the names the spec gives (resolve_inputs first).
BudgetResult run_budget(const BudgetSpec& spec, std::ostream* progress);
Table budget_table(const BudgetResult& r);
// Per method the configuration of smallest error among those that fit; nullptr when none fits.
const BudgetRow* best_at_budget(const BudgetResult& r, const std::string& integrator);

// An equal-total family of a method: its ok rows with substeps × iterations = total, by
// ascending substeps, and whether the error falls strictly from each to the next.
struct BudgetFamily {
  std::string integrator;
  long total = 0;
  std::vector<const BudgetRow*> rows;
  bool all_ok = true;
  bool falls = false;
};
std::vector<BudgetFamily> equal_total_families(const BudgetResult& r);

void write_budget_outputs(const std::filesystem::path& dir, const BudgetSpec& spec,
                          const BudgetResult& r);
bool plot_budget(const std::filesystem::path& csv, const std::string& title, const PlotOptions& opt,
                 std::ostream& err);

// The one call: check DIR, run, write DIR/budget.{csv,md,json}, plot, print (ctx.out); the
// pipeline of experiments/framework/study.hpp.
BudgetResult budget_study(const StudyInputs& in, BudgetSpec spec, const std::filesystem::path& dir,
                          const StudyContext& ctx = {});
const BudgetResult& budget_result(const StudyJob& job);

}  // namespace stiffbench

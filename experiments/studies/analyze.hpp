// What a method's coefficients say about it (`stiffbench analyze`), without running it: the
// analysis of core/theory/method_analysis.hpp for each integrator, written as tables and a plot.
//
// Each integrator is created from the registry with its defaults and its coefficients taken
// from the integrator itself: a Butcher tableau (kind explicit_rk when A is strictly lower
// triangular, dirk when lower triangular, irk otherwise), a Rosenbrock tableau, kick/drift
// coefficients or an additive (IMEX) pair of tables (kind imex_ark: the pair's order and embedded
// order from the additive order conditions, coupling ones included; then two more rows,
// NAME:explicit and NAME:implicit, each table analysed alone as a Runge–Kutta method: the
// explicit table's axis limits bound h·λ on f_E's spectrum, the implicit one's |R(∞)| and
// A-/L-stability tell what the pair does to f_I's). An integrator with none of them (BDF2, the
// graphics solvers, a library reference) is not coefficient-defined: its row says so and carries
// what its linear stability data give (axis and oscillator limits, A-stability), never a failure.
//
// Files (DIR/):
//   analyze.csv             one row per integrator (analyze_table below);
//   analyze_conditions.csv  integrator, order, tree, residual, error_coefficient, set: every order
//                           condition up to order 8 of the weights b (set `order`) and a
//                           Rosenbrock method's W-conditions up to order 6 (set `W`);
//   analyze_dispersion.csv  integrator, nu, amplification, phase_error: |R(iν)| and
//                           arg R(iν) − ν on ν ∈ [1e-2, 10] (log-spaced), for every method with a
//                           stability function R = P/Q;
//   analyze.md, analyze.json, analyze.png (two columns: |R(iν)| and |arg R(iν) − ν| against ν,
//                           log axes, one row of panels per integrator family).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/theory/linear_stability.hpp"
#include "core/theory/method_analysis.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"
#include "experiments/support/coefficients.hpp"

namespace stiffbench {

struct AnalyzeSpec {
  // The integrators' labels (StudyInputs::integrators). Empty: every registered integrator with
  // coefficients or linear stability data (analyze_integrators()).
  std::vector<std::string> integrators;
  int points = 121;  // ν samples of the dissipation/dispersion curves (--nu-points)

  // BadInput naming the flag: an integrator listed twice, --nu-points outside [2, 10000].
  void validate() const;
  nlohmann::json to_json() const;
};

// The registered integrators with coefficients or stability data, in registry order.
std::vector<std::string> analyze_integrators();

struct AnalyzedMethod {
  std::string integrator;
  std::string family;                // registry family
  bool coefficient_defined = false;  // `analysis` holds the analysis of its coefficients
  bool stopped = false;              // over --max-wall: only the name and a note "stopped: …"
  MethodAnalysis analysis;           // name, kind and claimed order are set for every method
  // Methods that are not coefficient-defined: what their linear stability data give.
  std::string stability_kind;  // LinearStability::kind; empty without stability data
  std::optional<AxisLimit> real_axis, imaginary_axis, oscillator;
  std::optional<bool> a_stable;
  bool limits_exact = false;  // from polynomial roots (false: BDF2's sampled search)
  // |R(iν)| and arg R(iν) − ν; empty without a stability function R = P/Q.
  std::vector<DispersionPoint> dispersion;
};

struct AnalyzeResult {
  std::vector<AnalyzedMethod> methods;  // in the order of the spec
};

// The analysis of integrator `label` of `in` (created with its defaults): its own row (for an
// additive pair the pair's order from the additive conditions, without the two tables' rows).
AnalyzedMethod analyze_integrator(const StudyInputs& in, const std::string& label,
                                  int points = 121);
// Analyses `in`'s integrators (the spec's integrators are `in`'s; a user's own methods are given
// as objects to resolve_inputs). Nothing is written to `progress` (the methods are analysed in
// parallel).
AnalyzeResult run_analyze(const StudyInputs& in, const AnalyzeSpec& spec,
                          std::ostream* progress = nullptr);
// The same on the names the spec gives (resolve_inputs first).
AnalyzeResult run_analyze(const AnalyzeSpec& spec, std::ostream* progress = nullptr);
// The one call: check DIR, analyse, write DIR/analyze.{csv,md,json}, analyze_conditions.csv and
// analyze_dispersion.csv, plot, print the summary (ctx.out).
AnalyzeResult analyze_study(const StudyInputs& in, AnalyzeSpec spec,
                            const std::filesystem::path& dir, const StudyContext& ctx = {});
const AnalyzeResult& analyze_result(const StudyJob& job);

// analyze.csv: integrator, kind, stages, claimed_order, order, stage_order, embedded_order,
// w_order, embedded_w_order, claimed_w_order (Rosenbrock: the W-conditions' order of b and b̂,
// and the method's claim), fsal, stiffly_accurate, residual_order_1 … residual_order_8 (max |wᵀΦ(t)
// − 1/γ(t)| over the trees of that order), error_norm_2, error_norm_max (of the error coefficients
// of order p+1), error_norm_2_next, error_norm_max_next (order p+2), max_coefficient,
// p_coefficients, q_coefficients (ascending powers joined by ';'), r_infinity, a_stable, l_stable,
// real_axis_limit (r: stable on [−r, 0]), imaginary_axis_limit (r: stable on [−ir, ir]),
// internal_amplification_real, internal_amplification_imag, ssp_coefficient,
// ssp_relative_tolerance (of the bisection that found a positive SSP coefficient),
// dissipation_order, dispersion_order, oscillator_limit (largest stable hω on x'' = −ω²x),
// embedded_p_coefficients, embedded_q_coefficients, embedded_r_infinity, embedded_a_stable,
// embedded_l_stable, embedded_real_axis_limit, embedded_imaginary_axis_limit (the embedded
// formula's stability function R̂ = P̂/Q̂ and its figures), notes. Reals at full precision; an
// unbounded limit is `unbounded`; a dissipation or dispersion order of `none`: none to the series'
// length (|R(iν)| = 1, or no phase error); empty where a figure does not apply (a not
// coefficient-defined method has kind `not coefficient-defined` and only its stability figures).
Table analyze_table(const AnalyzeResult& r);
Table analyze_conditions_table(const AnalyzeResult& r);
Table analyze_dispersion_table(const AnalyzeResult& r);
// The summary printed by the command and shown in the report: integrator, kind, order, W-order
// (Rosenbrock), stage order, error norm ‖τ^(p+1)‖₂, |R(∞)|, A-/L-stable, the embedded formula's
// |R̂(∞)| and A-/L-stable, real- and imaginary-axis limits (full precision), SSP coefficient
// (with the bisection's relative tolerance).
Table analyze_summary_table(const AnalyzeResult& r);

// Writes the CSV files, DIR/analyze.md and DIR/analyze.json.
void write_analyze_outputs(const std::filesystem::path& dir, const AnalyzeSpec& spec,
                           const AnalyzeResult& r);

// The plot of DIR/analyze_dispersion.csv (→ DIR/analyze.png); false (with a note) when no
// method has a stability function.
bool plot_analyze(const std::filesystem::path& dispersion_csv, const std::string& title,
                  const PlotOptions& opt, std::ostream& err);

}  // namespace stiffbench

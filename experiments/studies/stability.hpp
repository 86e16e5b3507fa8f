// Measured stability limits against linear theory (`stiffbench stability`).
//
// Measured: for each integrator the largest fixed step h_max at which a run is stable, found by
// bracketing (doubling/halving from a first guess) and bisection until (hi − lo)/lo <= rel_tol.
// A run at step h is STABLE when it completes with status ok (a Newton failure is not stable),
// its state stays finite, its max-norm never exceeds `norm_growth` × max(1, ‖y0‖∞) (the
// driver's blow-up check) and — for mechanical systems with an "energy" invariant — its energy
// never exceeds E0 + (growth − 1)·|E0|, checked at every step over a horizon of `periods`
// periods 2π/ω of the fastest mode (ω = the spectral radius below), and at least `min_steps`
// steps. The energy matters: on nonlinear models an unstable mode can saturate (a 1D chain's
// springs invert at amplitudes near the rest length) long before the norm grows tenfold. The
// energy threshold is relative to |E0|, so it needs an energy whose zero is the rest state
// (chains, the SPH drop, Kepler). A model whose energy has an arbitrary zero says so
// (Invariant::arbitrary_zero: a spring network under gravity, whose potential -m g·x is zero at
// the cloth's initial height), and `criterion = auto` then judges by the norm alone. Before,
// E0 of the 64×64 cloth was its initial spring energy, 0.31, while its energy moves between
// gravity, springs and motion; symplectic Euler's bounded O(h) energy error crossed 2 E0 and the
// row said unstable_for_all_h, with a growth of ×0.99999 per period. `criterion = energy` on
// such a model is BadInput. The initial state is
// perturbed first so that every mode is excited (an unexcited fastest mode only grows from
// round-off and hides the instability):
//   mechanical systems: x_i += ε·s·ξ_i with s the RMS deviation of x0 from its mean (1 if 0);
//   first-order systems: y_i += ε·max(|y0_i|, 1e-3·‖y0‖∞)·ξ_i, reflected to |y_i| where
//                        y0_i >= 0 (concentrations stay non-negative);
// ξ_i standard normal from `seed` (std::mt19937_64), ε = `perturbation`. Velocities of
// mechanical systems are not perturbed (pinned points stay pinned).
//
// Statuses (stability.csv):
//   ok                  h_max measured to rel_tol: the bisection's upper end grew (norm or
//                       energy criterion);
//   stable_up_to        no instability up to the largest step tried, h_cap = h_cap_factor × 2/ω
//                       (A-stable methods): h_max_measured is h_cap, a lower bound of the limit
//                       (limit_kind stable_up_to). A method predicted unbounded (stable for
//                       every h on the spectrum) gets one run at h_cap instead of the search
//                       (unless probe_unbounded); if that run is not stable the search runs
//                       downward from h_cap as for any other method, and a run that grew
//                       (rather than failed in the solver) is said in the row's message as
//                       contradicting the prediction;
//   solver_limit        the bisection's upper end ended in the Newton iteration or the linear
//                       solver (newton_failed, solver_error), not in growth: h_max_measured is
//                       the largest step that ran stably (empty when none did down to h_floor)
//                       and the message names the failing step and the solver's reason. Not a
//                       stability limit: A-stable methods report stable_up_to or solver_limit;
//   unstable_for_all_h  the largest stable step shrinks with the horizon: a run at 0.75·h_max
//                       over 8× the horizon is unstable (a method with a real stability
//                       interval is stable there on a linear problem), or no step down to
//                       h_floor is stable. h_max_measured is empty; the Markdown table gives the
//                       growth per period at the last unstable probe instead.
//   failed              the integrator cannot run at all, or a probe threw (its message in
//                       the Markdown table);
//   timeout             the row's bisection passed --max-wall (core/run_control.hpp); the
//                       probes so far are not reported as a limit.
//
// Predicted: the spectrum of ∂f/∂y at the perturbed initial state — exact (Eigen's eigensolver
// of the dense analytic Jacobian) when the model has one and dimension <= dense_limit, else the
// model's stiffness() estimate ρ placed on the ray of `ray` (auto: the imaginary axis ±iρ for
// mechanical systems, −ρ for first-order ones), else the eigenvalues of a finite-difference
// Jacobian (dimension <= dense_limit) — scaled into the method's region
// (predicted_step_limit of core/theory/linear_stability.hpp; mechanical systems through the
// oscillator test, which is what kick/drift methods need). Empty where the method has no stability
// data. The limits are exact (polynomial roots of |P|² − |Q|² for R = P/Q, the half-trace of a
// splitting; core/theory/linear_stability.hpp) except for multistep methods and splittings on
// damped modes (sampled). A prediction of 0 means unstable for every h > 0: an undamped (imaginary)
// eigenvalue and a method whose imaginary-axis limit is 0 (euler, heun, cash_karp, rkf45).
// A spectrum with a non-finite value (an overflowing stiffness() estimate, a Jacobian with inf
// or NaN entries) is no spectrum: no prediction (the row's no_prediction says why), never
// "unbounded".
//
// IMEX and operator-splitting methods on a split model (Integrator::explicit_part_stability,
// OdeSystem::has_imex_split): the implicit part is A-stable, so what limits the step is the
// explicit treatment of f_E; the prediction is that treatment's limit (the explicit table's R, or
// the explicit sub-integrator's) on the spectrum of ∂f_E/∂y — exact (eigenvalues of J - J_I, both
// analytic, dimension <= dense_limit), else the model's explicit_part_spectrum() estimate on its
// ray. It neglects the coupling of the parts (exact when they commute and f_I damps, e.g.
// advection and diffusion on a periodic grid: the measured limit can only be at or above it).
// On a mechanical split (x' = v in f_I) the spectrum is that of [[0, I], [∂a_E/∂x, ∂a_E/∂v]] and
// the method's map is its partitioned one (Integrator::partitioned_stability(): x by the implicit
// treatment, v by the explicit one), not the explicit table's R on ±iω.
// stability.json says per row what the prediction was made on (`predicted_on`: f, f_E, or
// "f_E, partitioned (x' = v in f_I)").
//
// Counters: the solver counters (SolveStats::counter_names()) of the run at h_max_measured are
// columns of stability.csv after status; empty where no step ran stably.
//
// Sweep: `sweep_param` = values repeats everything per value (a fresh model each time) and fits
// the log–log slope of h_max against |value| per integrator over the rows with status ok
// (−½ expected for spring k and SPH EOS stiffness, −1 for λ); the same slope of the predicted
// limits is reported beside it.
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"

namespace stiffbench {

struct StabilitySpec {
  std::string model;
  Params params;
  std::vector<std::string> integrators;
  std::string sweep_param;           // empty: no sweep
  std::vector<double> sweep_values;  // the values of sweep_param
  double rel_tol = 1e-3;             // bisection tolerance on h
  double periods = 500;              // horizon in periods of the fastest mode
  long min_steps = 200;              // and at least this many steps
  double energy_growth = 2;    // option `growth`: energy factor (mechanical systems with energy)
  double norm_growth = 10;     // blow-up factor on the max-norm (every system)
  double perturbation = 1e-3;  // ε
  unsigned long seed = 1;
  double h_cap_factor = 1e3;    // largest step tried: h_cap_factor × 2/ω
  long max_steps = 20'000'000;  // per probe run (also limits h_floor)
  std::string ray = "auto";     // auto | imag | real (for the stiffness() estimate)
  // auto: the energy criterion for mechanical systems with an "energy" invariant, the norm
  // alone otherwise; norm: the norm alone (models whose energy has an arbitrary zero, e.g.
  // gravity's potential with cloth at z = 0, where E0 is no scale); energy: require it.
  std::string criterion = "auto";
  Index dense_limit = 600;        // eigen-decompose the Jacobian up to this dimension
  std::optional<double> horizon;  // explicit horizon (time); else periods × 2π/ω
  // Methods predicted unbounded (A-stable on the spectrum): false — one run at the largest step
  // h_cap (stable_up_to when stable); true — the search of every other method (doubling from
  // 2/ω up to h_cap, bisection where a step fails).
  bool probe_unbounded = false;

  void validate() const;  // BadInput naming the bad flag
  nlohmann::json to_json() const;
};

// Parses "--sweep NAME=v1,v2,..." or "NAME=lo:hi:n" (n log-spaced values, lo and hi of one
// sign). BadInput naming --sweep on a malformed argument.
void parse_sweep(const std::string& arg, std::string& name, std::vector<double>& values);

struct StabilityRow {
  std::string model, integrator, param;  // param empty without a sweep
  double value = 0;                      // the swept value (unused without a sweep)
  std::optional<double> h_measured;      // empty for unstable_for_all_h / failed
  std::optional<double> h_predicted;     // empty without stability data or spectrum
  bool predicted_unbounded = false;      // linear theory: stable for every h (A-stable)
  std::string no_prediction;             // why neither h_predicted nor unbounded (else empty)
  double h_cap = 0;                      // the largest step tried (h_cap_factor × 2/ω)
  // Predicted unbounded and not probe_unbounded: one run at h_cap instead of the search.
  bool checked_at_cap = false;
  // ok | stable_up_to | solver_limit | unstable_for_all_h | failed | timeout
  std::string status;
  std::optional<SolveStats> counters;       // of the run at h_measured
  std::optional<double> growth_per_period;  // unstable_for_all_h: at the last unstable probe
  double growth_h = 0;                      // the step of that probe
  int probes = 0;                           // runs made
  double horizon = 0;                       // time horizon used at h_max
  std::string message;                      // failed, solver_limit: why
  // What the prediction was made on: "f" (the spectrum of ∂f/∂y) or "f_E" (an IMEX or
  // operator-splitting method on a split model: the explicit treatment's stability on the
  // spectrum of ∂f_E/∂y).
  std::string predicted_on = "f";
};

struct StabilityResult {
  std::vector<StabilityRow> rows;
  std::string spectrum_source;  // per model (last value of a sweep): how ω was obtained
  // The criterion the runs were judged by besides the norm: "energy" or "norm" (the norm alone),
  // and why `auto` left the energy out (its zero is arbitrary), else empty. Last value of a sweep.
  std::string criterion, criterion_note;
  // How the spectrum of ∂f_E/∂y was obtained (split models with an IMEX or splitting method
  // among the integrators; empty otherwise).
  std::string explicit_spectrum_source;
  struct Fit {
    std::string integrator;
    std::optional<double> measured_slope, predicted_slope;
    int points = 0;
  };
  std::vector<Fit> fits;  // sweeps only
};

// Measures every integrator of `in` on its model (per value of the sweep: a fresh model each
// time); the spec's model, params and integrators are `in`'s. Every set-up (unused --param keys,
// incompatible pairs, adaptive-only methods) is checked before the first run. Progress lines go
// to `progress` when non-null.
StabilityResult run_stability(const StudyInputs& in, const StabilitySpec& spec,
                              std::ostream* progress);
// The same on the names the spec gives (resolve_inputs first).
StabilityResult run_stability(const StabilitySpec& spec, std::ostream* progress);
// The one call: check DIR, run, write DIR/stability.{csv,md,json}, plot, print (ctx.out).
StabilityResult stability_study(const StudyInputs& in, StabilitySpec spec,
                                const std::filesystem::path& dir, const StudyContext& ctx = {});
const StabilityResult& stability_result(const StudyJob& job);

// Least-squares slope of log y against log x (at least two points, else empty).
std::optional<double> loglog_slope(const std::vector<double>& x, const std::vector<double>& y);

// What h_max_measured of a row is: "measured" (status ok or solver_limit: the largest stable step
// below a failing one, to rel_tol), "stable_up_to" (status stable_up_to: the largest step tried,
// a lower bound of the limit), empty without h_max_measured.
std::string limit_kind(const StabilityRow& row);

Table stability_table(const StabilityResult& r);  // the stability.csv contract
void write_stability_outputs(const std::filesystem::path& dir, const StabilitySpec& spec,
                             const StabilityResult& r);
// The plot of DIR/stability.csv: with a sweep h_max against the parameter (log–log, measured
// points, predicted lines), else measured and predicted h_max per integrator.
bool plot_stability(const std::filesystem::path& csv, const std::string& title,
                    const PlotOptions& opt, std::ostream& err);

}  // namespace stiffbench

// Energy drift: long fixed-step runs of a conservative model, the relative error of an
// invariant (energy by default) evaluated after EVERY step and written as a sampled time series.
//
// Relative error: e(t) = |I(t) - I0| / |I0| with I0 the invariant at the initial state; when
// |I0| <= kZeroInvariant the absolute error |I(t) - I0| is used instead. That covers I0 = 0 and
// the round-off of cancelling sums that are zero in exact arithmetic: the total momentum of the
// symmetric SPH drop starts at ~1e-17, and dividing by it gave "relative errors" of 20 for a
// momentum conserved to 1e-16. The threshold is absolute (invariants carry units). An invariant
// whose zero is arbitrary (Invariant::arbitrary_zero: a cloth's energy under gravity, whose
// potential is zero at the initial height) gets the absolute error too: divided by |I0| its error
// would depend on where the model put the origin. energy.md and energy.json say which error each
// invariant got, and why. A non-finite value counts as +inf.
//
// Sampling: a row every ceil(N/samples) steps, plus the initial state and the last step (so a run
// of N steps gives about samples + 2 rows, whatever N is). Each row carries the invariant and its
// error at that step and the maximum error over the steps since the previous row
// (max_rel_error_since_last), so the series shows every peak (a pericentre passage) although
// most steps are not written; the largest of these equals the maximum over the whole run.
//
// Summary per integrator, from every step (accumulated online, nothing stored per step):
//   max_rel_error    max over the run;  final_rel_error  at the last step;
//   drift_rate       least-squares slope of e(t) against t (Welford-style centred sums);
//   growth           max over the run / max over its first tenth (t <= t0 + (t_end - t0)/10):
//                    ≈ 1 for a bounded (symplectic) oscillation of the error, ≈ 10 for a linear
//                    secular drift; 1 when the error is identically 0, empty when the run ended
//                    before the first tenth did;
//   status           the driver's (ok, unstable on blow-up, newton_failed, ...). A run that
//                    fails keeps its rows up to its last good step; the other integrators go on.
// Other invariants of the model (angular momentum, momentum) get their maximum relative error,
// shown in energy.md (the CSV columns are the contract of DESIGN.md).
#pragma once

#include <cmath>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/driver.hpp"
#include "core/params.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"
#include "experiments/support/invariant_error.hpp"

namespace stiffbench {

struct EnergySpec {
  std::string model;
  Params params;
  std::vector<std::string> integrators;
  // Requested step; NaN: the model's suggested step (an error if it has none).
  double h = std::numeric_limits<double>::quiet_NaN();
  // Final time; NaN: the model's literature end time (an error if it has none).
  double t_end = std::numeric_limits<double>::quiet_NaN();
  long samples = 1000;               // rows per integrator in energy.csv (about)
  std::string invariant = "energy";  // which of the model's invariants is the series

  void validate() const;  // BadInput naming the bad flag
  nlohmann::json to_json() const;
};

struct EnergySample {
  double t = 0;
  double value = 0;                     // the invariant
  double rel_error = 0;                 // at this step
  double max_rel_error_since_last = 0;  // over the steps since the previous row (this one included)
};

// One integrator's run.
struct EnergyRun {
  std::string integrator;
  double h = 0;      // the step actually used, (t_end - t0)/N
  long steps = 0;    // N requested
  double t_end = 0;  // requested
  double t_reached = 0;
  double max_rel_error = 0;
  double final_rel_error = 0;
  // The same at the last step with its sign: (I(t) - I0)/|I0| (or I(t) - I0 where the error is
  // absolute): > 0 the method gained energy, < 0 it lost it (explicit Euler gains on an
  // oscillator, backward Euler loses). NaN when the invariant ended non-finite.
  double final_change = 0;
  double drift_rate = 0;               // per unit time (of the unsigned error)
  std::optional<double> growth_ratio;  // column `growth`: see the header comment
  // Other invariants: name and maximum error over the run (relative, or absolute when
  // invariant_error_is_absolute(I0)).
  std::vector<std::pair<std::string, double>> other_max_rel_error;
  SolveStats stats;  // status, message, counters, wall time
  std::vector<EnergySample> samples;
};

// The object-level call: any system and integrator object, nothing looked up by name.
struct EnergyRunOptions {
  double h = 0.01;
  double t_end = 1.0;
  long samples = 1000;
  std::string invariant = "energy";
  // Called after each tenth of the steps (1..10), for progress lines.
  std::function<void(int tenth, double t)> on_tenth = {};
};

// Runs `integ` on `sys` from its initial state with fixed steps. BadInput when the system has no
// such invariant (naming the ones it has), when the integrator is adaptive-only or cannot run on
// the system, or for a bad h / t_end.
EnergyRun measure_energy_drift(const OdeSystem& sys, Integrator& integ,
                               const EnergyRunOptions& opt);

struct EnergyResult {
  std::string model;
  std::string invariant;
  double initial_value = 0;    // I0
  std::string arbitrary_zero;  // Invariant::arbitrary_zero of the invariant
  std::vector<std::string> other_invariants;
  std::vector<double> other_initial_values;
  std::vector<std::string> other_arbitrary_zero;
  double h = 0;  // requested (spec.h or the suggested step)
  std::string h_source;
  double t_end = 0;
  std::string t_end_source;
  std::vector<EnergyRun> runs;
};

// Creates the model and integrators of `in` (make_setup: unused --param keys and incompatible
// pairs are BadInput before anything runs) and measures each integrator in turn; the spec's
// model, params and integrators are `in`'s. Progress lines go to `progress` when non-null.
EnergyResult run_energy(const StudyInputs& in, const EnergySpec& spec, std::ostream* progress);
// The same on the names the spec gives (resolve_inputs first).
EnergyResult run_energy(const EnergySpec& spec, std::ostream* progress);
// The one call: check DIR, run, write DIR/energy.{csv,md,json} and energy_summary.csv, plot,
// print (ctx.out).
EnergyResult energy_study(const StudyInputs& in, EnergySpec spec, const std::filesystem::path& dir,
                          const StudyContext& ctx = {});
const EnergyResult& energy_result(const StudyJob& job);

Table energy_table(const EnergyResult& r);          // the energy.csv contract (sampled rows)
Table energy_summary_table(const EnergyResult& r);  // the energy_summary.csv contract
// The summary with the other invariants' maxima and the wall time (energy.md, stdout).
Table energy_markdown_table(const EnergyResult& r);

// Writes DIR/energy.csv, DIR/energy_summary.csv, DIR/energy.md, DIR/energy.json ("spec":
// spec.to_json(); the h and t_end used as h_used/t_end_used with their sources), then draws
// DIR/energy.png (plot_energy). Returns whether the plot was drawn.
bool write_energy_outputs(const std::filesystem::path& dir, const EnergySpec& spec,
                          const EnergyResult& r, const PlotOptions& opt, std::ostream& err,
                          const std::string& title = "");

// The energy-drift plot from an energy.csv (DIR/energy.csv → DIR/energy.png): the relative
// error (max since the previous sample) against t, log y, one panel per integrator family.
bool plot_energy(const std::filesystem::path& csv, const std::string& title, const PlotOptions& opt,
                 std::ostream& err);

}  // namespace stiffbench

// Performance and data profiles over a suite of work-precision studies (`stiffbench profile`,
// docs/commands/profile.md).
//
// A suite is a folder of work-precision spec files (the report's format), one problem each. Every
// file of a suite must hold the same study settings: the same `integrators`, the same top-level
// keys with the same values (tolerance ladder, step ladder, reference, repeats, seed, ...) and
// the same [quick] table; only the problem may differ: `model`, the model's own [params] and
// `t_end` (the end of the problem's time interval, part of an initial value problem as in the
// IVP test set). A [params] key that is an integrator's parameter, not the model's, is a study
// setting. A suite that differs in any study setting is refused (BadInput, exit 2) before
// anything runs, naming both files and the key ("no per-problem tuning"). The shipped suites are
// suites/{stiff,mechanical}/, compiled into the library.
//
// Each problem runs as `stiffbench run FILE --out DIR/<problem> --resume` would (one unit per
// integrator, DIR/<problem>/{work_precision.csv,run.json}); a folder whose run.json records the
// same spec hash and whose CSV holds every unit is reused as it is (also the folder of
// `stiffbench merge` after `run --shard`/`--slurm`), one holding some units is completed
// (--resume), one holding another spec is refused unless --force (which replaces it; a run of
// the same spec is never started over). DIR/profile.json records the suite (not tau and cost):
// another --tau or --cost on the same DIR reuses every problem and rewrites DIR/profile.*.
//
// Cost of method m on problem p at accuracy τ (no interpolation): the least cost among the
// runs of m on p with status ok and error <= τ (error: the work-precision max-norm error at
// t_end against the exact solution or the reference); +infinity (unsolved) when there is none
// (never reaches τ, failed, unstable, timeout), and also when the runs' cost column is empty:
// a library that keeps no count of it (GSL's implicit steppers and lin_solves) is not ranked on
// a cost it does not report. Cost measures: f_evals (the f_evals column), wall (wall_s_median,
// seconds), linear_solves (lin_solves).
//
// Performance profile (Dolan & Moré 2002): r_{p,m} = cost_{p,m} / min_m' cost_{p,m'} (infinite
// when m does not solve p or no method does), ρ_m(α) = |{p : r_{p,m} <= α}| / |P|.
// Data profile (Moré & Wild 2009), budget κ in raw cost units (f evaluations, seconds, linear
// solves; not normalised per problem): d_m(κ) = |{p : cost_{p,m} <= κ}| / |P|.
// Both are step functions, written exactly at their breakpoints.
// Ranking at each τ and cost: by ρ_m(1) (the share of problems where m is the cheapest, ties
// counted for every tied method), then by the area under ρ_m over log2 α in [0, log2 α_max]
// (α_max the largest finite ratio of the table, 1 if none: (1/|P|) Σ_{p solved by m}
// (log2 α_max - log2 r_{p,m})), then by name.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/framework/spec_file.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"

namespace stiffbench {

// Cost measures of a profile.
inline const std::vector<std::string>& profile_cost_names() {
  static const std::vector<std::string> names = {"f_evals", "wall", "linear_solves"};
  return names;
}

struct ProfileProblem {
  std::string name;  // the file's stem without a leading "NN_": the folder DIR/<name>
  SpecFile spec;     // [quick] applied for --quick
};

struct ProfileSuite {
  std::string name;    // "stiff", "mechanical", or the folder given
  std::string source;  // "built-in" or the folder's path
  std::vector<ProfileProblem> problems;
  std::vector<std::string> methods;  // the suite's integrators (every file's)
  // The study settings every file shares (canonical form without model, params and t_end) and,
  // per problem, what differs: model, params, t_end. Recorded in profile.json.
  nlohmann::json shared, problem_settings;
};

// The built-in suites' names ("mechanical", "stiff").
std::vector<std::string> builtin_profile_suites();
// A built-in suite by name or a folder of spec files (*.toml, in name order); checked (every spec
// loads and configures, the same study settings everywhere) before anything runs.
ProfileSuite load_profile_suite(const std::string& suite, bool quick);
// A suite of a program's own specs (names from the file names); the same checks.
ProfileSuite make_profile_suite(const std::string& name, std::vector<SpecFile> specs, bool quick);

// Per problem (rows) and method (columns): the cost at one τ and cost measure; +infinity =
// unsolved, with the reason in `note`.
struct CostTable {
  std::vector<std::string> problems, methods;
  std::vector<std::vector<double>> cost;       // [problem][method]
  std::vector<std::vector<std::string>> note;  // [problem][method]: why unsolved ("" if solved)
};

// One point of a profile's step function: fraction(x) for x >= this x up to the next point.
struct ProfilePoint {
  double x = 0, fraction = 0;
};
// ρ_m(α) and d_m(κ) at one argument.
double performance_profile(const CostTable& t, std::size_t method, double alpha);
double data_profile(const CostTable& t, std::size_t method, double kappa);
// The breakpoints of every method's curve: x at 1 and at each finite ratio (performance) or
// each finite cost (data) of the table, sorted, with the method's fraction there.
std::vector<ProfilePoint> performance_curve(const CostTable& t, std::size_t method);
std::vector<ProfilePoint> data_curve(const CostTable& t, std::size_t method);
// The area under ρ_m over log2 α (see the ranking above).
double performance_area(const CostTable& t, std::size_t method);
// Method indices, best first (ρ(1), then area, then name).
std::vector<std::size_t> profile_ranking(const CostTable& t);

// The cost table of one τ and cost measure from the rows of each problem's work_precision.csv
// (`rows[p]` a Table with the run CSV's columns).
CostTable cost_table(const std::vector<std::string>& problems,
                     const std::vector<std::string>& methods, const std::vector<Table>& rows,
                     double tau, const std::string& cost);

struct ProfileOptions {
  std::string suite;                        // a built-in suite's name or a folder
  std::vector<double> taus = {1e-3, 1e-6};  // target accuracies, each > 0
  std::vector<std::string> costs = {"f_evals", "wall"};
  std::string out_dir = "results";
  bool quick = false;
  // Also write DIR/profile.html (experiments/output/html.hpp): every τ and cost as a section with
  // its plots as inline SVG, the cost table and the ranking (implies SVG plots).
  bool html = false;
  // Replace results of other specs in DIR/<problem>/ and DIR/profile.* (runs of the same spec
  // are always reused or completed, never started over).
  bool force = false;
  PlotOptions plot;
  void validate() const;  // BadInput naming --tau or --cost
};

struct ProfileResult {
  ProfileSuite suite;
  std::vector<double> taus;
  std::vector<std::string> costs;
  std::vector<CostTable> tables;         // [tau index * costs.size() + cost index]
  std::vector<std::string> reused, ran;  // problems
  // Every unit (problem x method) whose run did not end ok: unit_status "failed" (some setting's
  // run ended with a status other than ok: unsolved there) or "error" (the unit threw: no rows).
  struct UnitStatus {
    std::string problem, method, status, message;
  };
  std::vector<UnitStatus> not_ok;
  std::vector<std::string> disagreements;  // wall against counter rankings
  double wall_s = 0;
  const CostTable& table(std::size_t tau, std::size_t cost) const {
    return tables[tau * costs.size() + cost];
  }
};

// The profiles of a suite: runs or reuses each problem in DIR/<problem>/, then writes
// DIR/profile.{csv,md,json}, DIR/profile_status.csv (every problem x method with its unit
// status) and DIR/profile_<tau>_<cost>.png (performance and data panels) and prints the rankings
// on `out`. Progress and notes go to `err`. A unit that did not end ok is data, not a failure of
// the profile: its runs count as unsolved; it is listed in profile_status.csv, profile.md,
// profile.json ("units_not_ok") and on `err`.
ProfileResult run_profile(const ProfileSuite& suite, const ProfileOptions& opt, std::ostream& out,
                          std::ostream& err);
// `stiffbench profile`: load_profile_suite(opt.suite, opt.quick), then run_profile.
ProfileResult cmd_profile(const ProfileOptions& opt, std::ostream& out, std::ostream& err);

Table profile_csv_table(const ProfileResult& r);
// profile_status.csv: problem, method, unit_status (ok | failed | error), unit_message.
Table profile_status_table(const ProfileResult& r);
std::string profile_markdown(const ProfileResult& r);

}  // namespace stiffbench

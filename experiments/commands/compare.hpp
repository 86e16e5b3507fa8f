// Comparing two runs (`stiffbench compare OLD NEW`): the output folders of the same study (or of
// `report`, `profile` or `run`, holding several) run twice, e.g. before and after a change of a
// method, of the testbed or of the machine.
//
// Files are matched by their path relative to OLD and NEW (every *.csv and *.json below them;
// hidden files are left out; lines starting with '#' are comments, e.g. the key of a reference
// cache and its note with the time it took).
//  - Run records: every JSON file that records a run (run_metadata in
//  experiments/output/output.hpp,
//    at its top or under "metadata" for `run`): the spec (every differing key), the experiment,
//    stiffbench, Eigen, SUNDIALS and GSL versions, git revision, compiler, build type, flags,
//    CPU model, thread count, seed and caller. Dates and command lines are not compared.
//  - Tables: every CSV. Rows are matched by their key columns (kCompareKeyColumns that the
//    table has, e.g. model, integrator, h or setting; budget's grid by h and total_iterations,
//    which fix substeps and iterations; a key seen twice gets "#2", "#3", ... in
//    file order; without key columns, by row number). Every other column both tables have is
//    compared cell by cell: text exactly, counters exactly (compare_counter_columns(), and any
//    column whose every value in both tables is an integer), other numbers within
//    |new - old| <= rtol·max(|old|, |new|) + atol (NaN equals NaN). Timing columns (a name
//    containing "wall", starting with "ms_per_frame", or `repeats`/`timed_runs`, whose counts
//    follow the measured times) and the rows of measured wall-time costs (`cost` = wall, in
//    `profile.csv`) are not compared: they are measurements of the machine, reported apart.
//  - Timing: a row with a median and a bootstrap 95% interval (work-precision: wall_s_median,
//    wall_s_ci_low, wall_s_ci_high, repeats; budget: ms_per_frame_*, timed_runs) gets both
//    intervals and a verdict: `faster` when NEW's interval lies wholly below OLD's, `slower`
//    when wholly above, `not resolved` when they overlap or when either side has fewer than
//    kCompareMinTimedRuns runs. A single time (wall_s of convergence) is never resolved.
//
// The runs agree (same()) when no row changed beyond the tolerance and no row or file is on
// one side only; columns on one side only are listed but do not count (a newer testbed may add
// a column).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/output/output.hpp"

namespace stiffbench {

// The columns that identify a row, looked up in each table in this order.
inline const std::vector<std::string> kCompareKeyColumns = {
    "unit", "problem", "model", "integrator", "method", "setting", "h",     "total_iterations",
    "t",    "param",   "value", "mode",       "nu",     "tree",    "check", "system",
    "tau",  "cost",    "kind"};
// The counters: the integer fields of SolveStats (steps, f_evals, jac_evals, lin_solves and the
// solver counters newton_iters ... fi_evals), in its order. Compared exactly, and each one that
// differs is listed with its ratio (any other column whose every value is an integer, e.g. a
// claimed order, is compared exactly too).
std::vector<std::string> compare_counter_columns();
// The first of these a table has is its error column (its ratio is reported for every row).
inline const std::vector<std::string> kCompareErrorColumns = {
    "error", "local_error", "max_rel_error", "strain_error_max", "rel_error"};
// Disjoint bootstrap intervals of the median are a verdict only with at least this many runs on
// each side. With n <= 5 runs the interval spans the fastest to the slowest run, and two
// samples of n and m runs of one distribution have disjoint ranges with probability
// 2·n!·m!/(n+m)!: 1/3 for 2 and 2, 1/10 for 3 and 3, 1/35 for 4 and 4 (below 5%), 1/126 for 5
// and 5.
constexpr int kCompareMinTimedRuns = 4;

struct CompareOptions {
  double rtol = 1e-12;  // relative tolerance on real numbers (not on counters or text)
  double atol = 0;      // absolute tolerance on real numbers
};

// One difference between the run records (JSON) of OLD and NEW.
struct RecordDifference {
  std::string file;                  // relative path
  std::string key;                   // e.g. "git_revision", "spec.integrators"
  std::string old_value, new_value;  // JSON text; "(absent)" when missing
};

// Wall time of one row on both sides.
struct TimingComparison {
  std::string quantity;  // the median's column: wall_s_median, wall_s, ms_per_frame_median
  double old_median = 0, old_low = 0, old_high = 0;
  double new_median = 0, new_low = 0, new_high = 0;
  int old_runs = 0, new_runs = 0;  // 1 for a single time
  bool has_interval = false;
  std::string verdict;  // faster | slower | not resolved (...) | not measured
};

// One row of a table on both sides.
struct RowComparison {
  std::string file;  // relative path of the CSV
  std::string key;   // "integrator=rk4, h=0.01" (or "row N")
  enum class Presence { both, old_only, new_only } presence = Presence::both;
  bool changed = false;  // a compared cell differs beyond the tolerance, or one side only
  // The cells that differ beyond the tolerance: "COLUMN OLD -> NEW (ratio R)".
  std::vector<std::string> differences;
  std::string error_column, error_old, error_new;  // empty when the table has none
  std::string f_evals_old, f_evals_new;
  // Counters whose values differ, "NAME OLD -> NEW (ratio R)"; empty: all equal.
  std::vector<std::string> counter_changes;
  bool has_timing = false;
  TimingComparison timing;
};

struct FileComparison {
  std::string file;  // relative path
  enum class Presence { both, old_only, new_only } presence = Presence::both;
  bool is_table = false;  // a CSV (else a JSON run record)
  long rows = 0, changed_rows = 0;
  std::vector<std::string> key_columns;
  std::vector<std::string> notes;  // columns on one side only, a JSON that is not a run record
};

struct CompareResult {
  std::filesystem::path old_dir, new_dir;
  CompareOptions options;
  std::vector<FileComparison> files;
  std::vector<RecordDifference> records;
  std::vector<RowComparison> rows;  // every row of every table, OLD's order then NEW's extras

  long changed_rows() const;
  long files_on_one_side() const;
  // No row changed and no row or file on one side only.
  bool same() const { return changed_rows() == 0 && files_on_one_side() == 0; }
};

// "R" of new/old: "1" when equal, "1+2.3e-10" / "1-4e-12" close to 1, else 6 significant
// digits; "-" when either is not a number, "inf" when only old is 0.
std::string compare_ratio(double old_value, double new_value);

// Compares OLD and NEW (see above). BadInput when either is not a folder, when they hold no
// CSV file of the same relative path, when an option is not a finite non-negative number, or
// when a CSV row has another number of fields than its header (naming the file and line).
CompareResult compare_runs(const std::filesystem::path& old_dir,
                           const std::filesystem::path& new_dir, const CompareOptions& opt = {});

// compare.csv: one line per row (file, row, status, differences, error and f_evals on both
// sides with their ratio, counters, wall time with intervals and verdict).
Table compare_table(const CompareResult& r);
// The summary: verdict, run-record differences, and per table its changed rows and (when
// timed) every row's error and f_evals ratios, counters and wall-time verdict.
std::string compare_markdown(const CompareResult& r);
// DIR/compare.{csv,md,json} (the JSON: run metadata with the spec of the comparison, the
// record differences and the counts).
void write_compare_outputs(const std::filesystem::path& dir, const CompareResult& r);
// The spec recorded in DIR/compare.json: OLD and NEW (absolute) and the tolerances.
nlohmann::json compare_spec(const std::filesystem::path& old_dir,
                            const std::filesystem::path& new_dir, const CompareOptions& opt);

// What `stiffbench compare` does: checks OLD, NEW and the options, checks DIR (it can be written,
// it is not inside OLD or NEW, it holds no compare.* of another comparison unless force_output()),
// compares and writes DIR/compare.{csv,md,json}.
CompareResult compare_study(const std::filesystem::path& old_dir,
                            const std::filesystem::path& new_dir, const CompareOptions& opt,
                            const std::filesystem::path& out_dir, std::ostream* note);

}  // namespace stiffbench

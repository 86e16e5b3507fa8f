// The run engine of `stiffbench run` (README "Spec files and sweeps").
//
// Expansion: the sweep dimensions are the list-valued top-level keys (sorted by name), then the
// list-valued [params] keys (sorted by name); the points are their cartesian product with the
// LAST dimension varying fastest. A work unit is one point × one integrator (integrators in
// spec order, fastest): unit index = point index × (number of integrators) + integrator index.
// A region spec has one unit per point (all its integrators).
//
// Rows: OUT/<kind>.csv (kind with '-' as '_') holds, per row, `unit` (the unit index),
// `unit_rows` (how many rows that unit wrote), one column per sweep dimension (its --set name,
// prefixed `spec.` where it collides with a study column), the study's own columns (those of
// the single-experiment CSV; energy: energy_summary.csv's; region: region_limits.csv's), and
// `unit_status` (ok | failed: a row's status is not ok | error: the unit threw) with
// `unit_message`. Units are appended as they finish (one line per write, flushed); at the end
// the file is rewritten sorted by unit. --resume keeps the units whose rows are all present
// (a torn last line is dropped) and runs the others. With every unit present (unsharded run,
// complete merge) the rows are also written as a Markdown table, OUT/<kind>.md.
#pragma once

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace stiffbench {

// The most units (points x integrators) one spec may expand to; a larger sweep is refused before
// anything is expanded (split it into several spec files, or shard it across runs).
inline constexpr long kMaxSweepUnits = 100000;

class StudyJob;
struct SpecFile;

// The study of a spec without sweep dimensions (a report section), checked like a point of
// `run` (names, parameters, options; BadInput naming the file, line and key); a spec with a
// list-valued key is BadInput. The reference cache goes to `cache_dir` (empty: none).
std::unique_ptr<StudyJob> make_spec_job(const SpecFile& spec, const std::string& cache_dir);

// Exit code of `run` and `merge` when a unit failed or (merge) units are missing.
inline constexpr int kExitRowsFailed = 3;

struct RunOptions {
  std::string spec_file;
  std::vector<std::string> sets;  // --set KEY=VALUE
  std::string out_dir = "results";
  bool resume = false;
  int shard_index = 0, shard_count = 1;  // --shard I/N
  bool check_only = false;               // --check: validate and print the expansion
  int slurm_tasks = 0;                   // --slurm N: write job scripts instead of running
  std::string partition, time_limit;     // --partition, --time
  bool force = false;                    // --force: replace a run of another spec in the folder
};

// Returns the exit code (0, or kExitRowsFailed). BadInput for any spec or option error, before
// any unit runs.
int run_spec(const RunOptions& opt, std::ostream& out, std::ostream& err);

// `stiffbench merge --out OUT DIR...`; returns 0, or kExitRowsFailed when units are missing or
// failed. BadInput when the folders hold different specs.
int merge_shards(const std::string& out_dir, const std::vector<std::string>& dirs,
                 std::ostream& out, std::ostream& err, bool force = false);

// The same for a spec already loaded (a suite's spec, built in or with [quick] applied:
// `stiffbench profile`); opt.spec_file and opt.sets are not used.
int run_loaded_spec(const SpecFile& spec, const RunOptions& opt, std::ostream& out,
                    std::ostream& err);
// The record of a spec (what OUT/run.json holds under "spec"): the canonical spec after every
// method file among its integrators is registered and replaced by its method's name, with
// "method_files" naming each file and its content hash. Resolving registers the files.
nlohmann::json spec_record(const SpecFile& spec);
// The hash `run` records in OUT/run.json (spec_hash): of spec_identity(spec_record(spec)), so an
// edited method file makes another spec and an unchanged one (from any path) the same spec.
std::string spec_hash(const SpecFile& spec);

// "I/N" of --shard (BadInput naming --shard unless 0 <= I < N).
void parse_shard(const std::string& arg, int& index, int& count);

}  // namespace stiffbench

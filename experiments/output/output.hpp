// File output owned by the experiments layer: tables as CSV and Markdown, JSON metadata, and
// atomic writes (temporary name, then rename) so an interrupted run never leaves a truncated
// table.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/solve_stats.hpp"

namespace stiffbench {

struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  std::string to_csv() const;
  // GitHub-flavoured Markdown, each cell through markdown_escape (below).
  std::string to_markdown() const;
};

// Text for one Markdown table cell: a '|' escaped (a backslash before it), so that a message
// quoting |E0| stays in its cell, and line breaks as spaces.
std::string markdown_escape(const std::string& text);

// One CSV field: line breaks become spaces (one record per line, so `run` can append and resume
// line by line), quoted (with "" for ") when it holds ',' or '"'.
std::string csv_field(const std::string& s);
// The fields joined by ',' with a final newline.
std::string csv_line(const std::vector<std::string>& fields);

// The 64-bit FNV-1a hash (Fowler, Noll, Vo) of `s`, continuing from `h`; as 16 hex digits. Names
// the reference cache files and identifies spec files of `run`.
inline constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;
std::uint64_t fnv1a64(std::string_view s, std::uint64_t h = kFnvOffset);
std::string hex16(std::uint64_t x);

// The least-squares slope of y against x (centred sums); empty with fewer than two points or
// when every x is the same. The one fit behind observed orders, log-log slopes of stability
// limits and growth rates.
std::optional<double> least_squares_slope(const std::vector<double>& x,
                                          const std::vector<double>& y);

// Full precision (round-trips through text): for values in CSV files.
std::string format_full(double x);
// Short scientific form for Markdown tables and progress lines.
std::string format_short(double x, int digits = 3);
// Fixed-point form with `digits` decimals (observed orders).
std::string format_fixed(double x, int digits = 3);

// The largest input file (method, spec, suite file) the testbed reads: 4 MiB, far above any real
// one (a 200-stage tableau written with expressions is well under 1 MiB).
inline constexpr std::uintmax_t kMaxInputFileBytes = 4u << 20;
// The text of an input file named by the user, `what` saying which kind ("method file", "spec
// file"). BadInput, before anything is read, for a path that does not exist, a folder, anything
// but a regular file (a FIFO would block, /dev/zero never ends) or a file over
// kMaxInputFileBytes; a symlink to a regular file is followed.
std::string read_input_file(const std::filesystem::path& path, const std::string& what);

// Whether `text` is well-formed UTF-8 (RFC 3629: no overlong forms, no surrogates, at most
// U+10FFFF). Every name and path a run records goes into its JSON, which holds UTF-8 only.
bool valid_utf8(std::string_view text);

// `text` with each control character (below 0x20, 0x7f) written as \n, \t, \r or \xNN (and,
// when `text` is not valid UTF-8, every byte >= 0x80 as \xNN), to show a bad value in a message
// without letting it act on the terminal.
std::string printable(const std::string& text);
// BadInput "WHERE: key 'KEY': holds a control character (code N at character I) ..." when `text`
// holds a byte below 0x20 or 0x7f (DEL) — other than newline and tab where `multiline` — so a
// text field of an input file cannot move the cursor, clear the terminal or hide a line when it
// is printed.
void require_printable(const std::string& text, const std::string& where, const std::string& key,
                       bool multiline = false);

// Creates an empty file DIR/PREFIXxxxxxx with a random suffix, exclusively (O_CREAT | O_EXCL:
// never through an existing file or a symlink) and returns its path; std::runtime_error with the
// system's reason when it cannot.
std::filesystem::path create_exclusive_file(const std::filesystem::path& dir,
                                            const std::string& prefix);

// Writes `content` to PATH atomically: first to a temporary file `.NAME.tmp.XXXXXX` in PATH's
// folder (hidden, created exclusively under a random suffix, so it cannot collide with a user's
// file or with another process writing the same table, nor be a planted symlink), then renamed
// over PATH; a write error names the system's reason (e.g. "No space left on device"). When writing
// the temporary fails or throws, the temporary is removed before the error propagates: no `*.tmp*`
// is left.
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

// The same for a file written as a stream, so that a large file (a long trajectory) is never
// held in memory: the text goes to the temporary as it is produced, commit() renames it over
// PATH. Destroyed without commit() (an exception, a failed run that writes nothing), the
// temporary is removed.
class AtomicFileStream {
 public:
  explicit AtomicFileStream(std::filesystem::path path);
  ~AtomicFileStream();
  AtomicFileStream(const AtomicFileStream&) = delete;
  AtomicFileStream& operator=(const AtomicFileStream&) = delete;
  std::ostream& stream() { return file_; }
  // Closes the temporary and renames it over PATH; std::runtime_error when writing failed.
  void commit();

 private:
  std::filesystem::path path_, tmp_;
  std::ofstream file_;
  bool committed_ = false;
};

// A claim on an output folder for the length of one command: DIR/.stiffbench.lock, created
// exclusively, holding the process id, the start time and the command line. A second command
// writing into DIR meanwhile (another terminal, another job) finds it and is refused with
// BadInput naming the folder and the other run, so two runs never mix or overwrite each other's
// files. A lock whose process is gone (a killed run) is taken over, with a note. Released (the
// file removed) when the claim is destroyed, also on an exception.
class FolderClaim {
 public:
  FolderClaim(const std::filesystem::path& dir, std::ostream* note = nullptr,
              const std::string& flag = "--out");
  ~FolderClaim();
  FolderClaim(const FolderClaim&) = delete;
  FolderClaim& operator=(const FolderClaim&) = delete;

 private:
  std::filesystem::path lock_;
};

// Creates DIR and checks that a file can be written there, before an experiment runs; BadInput
// naming `flag`, the directory and the reason otherwise (and nothing is left behind).
void require_output_dir(const std::filesystem::path& dir, const std::string& flag = "--out");
// The same for an output file: its folder can be created and written, and FILE is not a folder.
void require_output_file(const std::filesystem::path& file, const std::string& flag = "--out");
// Removes the folders require_output_dir created in this process that are still empty: called
// when a command ends in bad input, so a refused run leaves no trace.
void remove_created_output_dirs();

// Output safety (README "Existing results: --force and --resume"): results are never replaced
// silently. Every experiment records the spec of its results in a JSON file in its output folder
// (`record`: NAME.json for the studies, run.json for `run` and `merge`, solve.json for `solve
// --frames`, report.json for `report`), under the key "spec". Before anything runs, a command
// calls check_existing_results with the spec its run would record (no wall times, dates, thread
// counts or output paths: only what determines the results). Only the files of this experiment
// count (`record` and `results`, names relative to DIR); other files in DIR are not looked at.
//  - DIR holds none of them: nothing to do (returns false).
//  - `record` holds the same spec (compared as JSON after a round trip through text, so NaN and
//    null agree): the results are recomputed and replaced; a one-line note goes to `note`
//    (when not null) and the function returns true.
//  - `record` holds a different spec, is not valid JSON or has no "spec", or a result file exists
//    without a record: BadInput naming the folder, the file and (for a different spec) the
//    differing keys with both values (spec_difference), telling the user to choose another --out or
//    pass --force; nothing is written or removed. With `force` the results are replaced instead (a
//    note to `note`; returns true).
// A program linking the library calls it before write_convergence_outputs & co. the same way
// (the *_study functions do, with force_output()).
bool check_existing_results(const std::filesystem::path& dir, const std::string& record,
                            const std::vector<std::string>& results, const nlohmann::json& spec,
                            bool force, std::ostream* note, const std::string& flag = "--out");
// The usual case of a study writing DIR/NAME.{csv,md,json,png,svg} (and `extra` files, e.g.
// energy_summary.csv): check_existing_results with NAME.json as the record.
bool check_study_output(const std::filesystem::path& dir, const std::string& name,
                        const nlohmann::json& spec, bool force, std::ostream* note,
                        const std::vector<std::string>& extra = {});
// A spec record's identity: the record with "method_files" reduced to {method: content hash}
// (where a method file was read from is not part of the spec; its content is). Two runs are of
// the same spec when their identities are equal; `run` hashes it (spec_hash).
nlohmann::json spec_identity(const nlohmann::json& spec);
// Every difference between a recorded spec and a requested one (their identities, after a round
// trip through JSON text): first each method file whose content changed ("method file F
// (method 'm') changed since the run: content hash A there, B here") or that is new or gone,
// then every other key as "KEY = A there, B here" (nested keys joined with '.'; "(absent)" for a
// missing key). Empty when they are the same spec.
std::vector<std::string> spec_differences(const nlohmann::json& recorded,
                                          const nlohmann::json& requested);
// spec_differences joined with "; " (the first four, then "and N more"); empty when equal.
std::string spec_difference(const nlohmann::json& recorded, const nlohmann::json& requested);
// --force of the command line: set by cli_main() for the duration of a command (false again
// when it returns). A library program may set it before calling the *_study functions.
void set_force_output(bool force);
bool force_output();

// The runs of a study that did not end with status ok, for its Markdown report: a heading and
// one item per run, "- WHAT: STATUS: MESSAGE" (the CSV keeps only the status column, whose
// names are a contract). Empty when every run ended ok.
struct RunNote {
  std::string what;  // e.g. "rk4, h = 1.1e-08"
  const SolveStats* stats;
};
std::string failed_runs_markdown(const std::vector<RunNote>& runs);

// What run metadata records of a run's model (the caller describes it: a registered model or a
// user's system).
struct ModelRecord {
  std::string name, description, source;
  bool built_in = true;
};
// Metadata common to every experiment: spec (as given: the caller records the method files it
// names), versions (stiffbench, Eigen, SUNDIALS, GSL), compiler, build type, flags, git revision,
// CPU model, thread count (OpenMP max threads), seed (the spec's "seed"; null when the study has
// none), date, command line, and `model` when given. (run_metadata(experiment, spec) in
// experiments/framework/catalog.hpp fills in the method files and the registered model.)
nlohmann::json run_metadata(const std::string& experiment, const nlohmann::json& spec,
                            const std::optional<ModelRecord>& model);
// The CPU's "model name" in /proc/cpuinfo ("unknown" where there is none).
std::string cpu_model();

// The command line recorded in run metadata: set by cli_main() for the duration of its run
// (cleared again when it returns, so later library calls in the same process record none).
void set_command_line(int argc, char** argv);
void clear_command_line();

}  // namespace stiffbench

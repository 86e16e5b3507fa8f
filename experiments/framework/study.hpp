// The study framework: every experiment kind (convergence, local-error, work-precision,
// stability, region, energy, and any later one, a user's own included) is one StudyKind in one
// registry. A kind declares its options once, in the ParamSpec/Bounds vocabulary of models and
// integrators, plus a function that turns resolved options into a configured StudyJob. From
// that single declaration come
//   - the command `stiffbench NAME` with one flag per option (`t_end` is `--t-end`) and --help,
//   - the keys of a spec file of `kind = "NAME"` and their validation (file:line:column),
//   - the sweep axes of `stiffbench run` (any list-valued option),
//   - the spec recorded in NAME.json and compared by the output-safety check,
//   - `stiffbench describe NAME`, which prints the options table.
// Every study then goes through one pipeline (run_study): check the output folder, run with
// progress and run control, write its tables atomically, plot, print the summary.
//
// Studies run on objects: a StudyTarget names a registered model and integrators, or carries a
// user's own system and integrator objects, which the study sees under their names for the
// duration of the call only (nothing is registered process-wide).
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"

namespace stiffbench {

// A user's own system and integrator objects for a study (nothing is registered by name).
struct StudyObjects {
  // The system: a fresh copy per run. Its results carry the spec's model name when given, else
  // the system's name(); that name must not be a registered model's.
  SystemFactory system;
  // Integrators, run after the spec's named ones under their info().name.
  std::vector<IntegratorFactory> integrators;
  bool empty() const { return !system && integrators.empty(); }
};

// What a study runs on.
struct StudyTarget {
  std::string model;                     // a registered model (or the name of `system`)
  Params params;                         // model and integrator parameters (--param)
  std::vector<std::string> integrators;  // registered integrators, run in this order
  StudyObjects objects;                  // a user's own system and integrators (optional)
};

// Settings of one invocation, passed to the pipeline instead of process-wide flags.
struct StudyContext {
  bool force = false;                // replace results of a different spec in the folder
  PlotOptions plot;                  // --svg
  std::ostream* progress = nullptr;  // progress lines (stderr on the command line)
  std::ostream* out = nullptr;       // the summary table and "wrote ..." lines
  std::ostream* err = nullptr;       // notes and warnings
  std::string title;                 // plot title (empty: the job's default title)
  std::string cache_dir;             // reference cache folder (convergence; empty: none)
  bool use_output_cache = true;      // one-off commands: the cache lives in --out
};

// A study configured from resolved options: run it, then write and summarise its results.
class StudyJob {
 public:
  virtual ~StudyJob() = default;
  // What determines the results (recorded in NAME.json, compared before a run).
  virtual nlohmann::json spec_json() const = 0;
  // Integrators besides the studied ones whose parameters the study consumes (a reference).
  virtual std::vector<std::string> helper_integrators() const { return {}; }
  virtual void run(std::ostream* progress) = 0;
  // The rows of `stiffbench run` for this job (the study's CSV contract; energy: the summary).
  virtual Table unit_table() const = 0;
  // DIR/STEM.{csv,md,json} and the kind's extra files; draws the plot, returns whether it did.
  virtual bool write(const std::filesystem::path& dir, const std::string& title,
                     const PlotOptions& plot, std::ostream& err) const = 0;
  // The table printed after a one-off command.
  virtual void print_summary(std::ostream& out) const = 0;
  // The report's text after a section's links and plot: the section note completed by what
  // the run found (reference, spectrum) and a summary table.
  virtual std::string report_markdown(const std::string& note) const = 0;
  virtual std::string default_title() const = 0;
};

struct StudyKind {
  std::string name;     // the command and spec-file kind, e.g. "work-precision"
  std::string stem;     // file stem of its outputs, e.g. "work_precision"
  std::string summary;  // one line: what it measures and writes
  bool takes_model = true;
  bool model_required = true;        // fidelity: the model is optional (per-mode part)
  bool takes_params = true;          // region: a method's coefficients only
  bool integrators_required = true;  // region: default every method with stability data
  // `run`: one unit per integrator; false: one unit per point with every integrator (region).
  bool unit_per_integrator = true;
  // The command also takes the integrators as positional arguments (`analyze rk4,dopri5 gauss6`),
  // joined with --integrators.
  bool positional_integrators = false;
  // --integrators' help when it is optional and does not select (recommend: it adds to the
  // candidates); empty: "default: every integrator the study applies to".
  std::string integrators_help;
  std::vector<ParamSpec> options;         // the study's own options, declared once
  std::vector<std::string> required;      // options that must be given
  std::vector<std::string> extra_files;   // besides STEM.{csv,md,json}, e.g. energy_summary.csv
  std::vector<std::string> unit_columns;  // the columns of StudyJob::unit_table()
  // Builds the job from resolved options (every declared key with a default is present; an
  // option without default is present only when given). BadInput naming the option for values
  // the declaration cannot express (combinations, lists).
  std::function<std::unique_ptr<StudyJob>(const StudyTarget&, const Params& options,
                                          const StudyContext&)>
      make;
};

// The registry (built-in studies first, then register_study's in order).
const std::vector<StudyKind>& study_kinds();
const StudyKind* find_study(const std::string& name);
const StudyKind& study_kind(const std::string& name);  // BadInput listing the known ones
std::vector<std::string> study_names();
// Adds a study kind (a user's own): from then on it has a command in cli_main, spec files and
// `describe`. A name already taken is std::logic_error.
void register_study(StudyKind kind);

// Resolves a study's options: declared defaults overlaid with `given`; type, range and choices
// checked. `how` names an option in messages (the command line: "--t-end", a spec file: its
// file:line:column and key). BadInput for an unknown key (with a did-you-mean), a bad value or a
// missing required option.
Params resolve_study_options(const StudyKind& kind, const Params& given,
                             const std::function<std::string(const std::string&)>& how);
// "--t-end" for "t_end".
std::string option_flag(const std::string& key);

// The options table of `stiffbench describe STUDY`.
void describe_study(const StudyKind& kind, std::ostream& out);

// Objects of a StudyTarget (a user's system and integrators) made visible by name to the
// registries (model_registry(), integrator_registry()) of this thread while the scope lives.
// Names of registered models or integrators are BadInput. Used by run_study and make_study.
class ScopedStudyObjects {
 public:
  // Sets `model` (when objects.system is given) and appends the objects' integrator names.
  ScopedStudyObjects(const StudyObjects& objects, std::string& model,
                     std::vector<std::string>& integrators);
  ~ScopedStudyObjects();
  ScopedStudyObjects(const ScopedStudyObjects&) = delete;
  ScopedStudyObjects& operator=(const ScopedStudyObjects&) = delete;

 private:
  bool active_ = false;
};

// Configures a job from a target whose objects are in scope (options resolved with `how`).
std::unique_ptr<StudyJob> make_study(const StudyKind& kind, const StudyTarget& target,
                                     const Params& options, const StudyContext& ctx,
                                     const std::function<std::string(const std::string&)>& how);

// The pipeline of a one-off study, for the command line and for programs: checks that DIR can
// be written and holds no results of a different spec (unless ctx.force), runs the study
// (progress to ctx.progress), writes DIR/STEM.{csv,md,json} and the extra files, draws the plot
// (warnings to ctx.err), and prints the summary and the files written to ctx.out. Returns the
// job, whose result accessors the study's own header offers (e.g. convergence_result()).
std::unique_ptr<StudyJob> run_study(const std::string& kind, StudyTarget target,
                                    const Params& options, const std::filesystem::path& dir,
                                    StudyContext ctx);
// The same pipeline for a job already configured (the typed one-call functions of each study,
// e.g. convergence_study with StudyObjects); the caller keeps the job's objects in scope.
void run_study_job(const StudyKind& kind, StudyJob& job, const std::filesystem::path& dir,
                   const StudyContext& ctx);

// One resolution of the default step and end time for every study: the given value when set
// (not NaN; 0 counts as unset for `allow_zero_unset`), else the model's suggested step / its
// literature end time, else `fallback` when given. BadInput naming the flag otherwise.
struct Resolved {
  double value = 0;
  std::string source;  // "--h", "suggested step: <rule>", "the model's literature end time"
};
Resolved resolve_step(const OdeSystem& sys, double given, const std::string& model,
                      const std::function<Resolved()>& fallback = nullptr);
Resolved resolve_end_time(const OdeSystem& sys, double given, const std::string& model);
// NaN when the option is absent (not given and no default), else its value.
double optional_real(const Params& options, const std::string& key);

}  // namespace stiffbench

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
// Studies run on a StudyInputs value (experiments/framework/resolve.hpp): what the command line,
// a spec file or a program said (a StudyTarget: names, method files, variants, a user's own
// system and integrator objects), resolved once before the study is configured.
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
#include "experiments/framework/resolve.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"

namespace stiffbench {

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

// The family of integrator `label` of `in` (to_string(Family)), "" for an unknown label.
std::string integrator_family(const StudyInputs& in, const std::string& label);
// The family of a registered integrator, "" for an unknown name (FamilyOf for plots drawn outside
// a study: `stiffbench plot`, jobs that do not set their own).
std::string registered_family(const std::string& name);

// A study's functions over its typed spec and result. One generic job, TypedStudyJob, runs any
// study from them; a study declares a StudyFunctions value instead of a job class.
template <class Spec, class Result>
struct StudyFunctions {
  std::function<Result(const StudyInputs&, const Spec&, std::ostream* progress)> run;
  std::function<Table(const Spec&, const Result&)> unit_table;
  // DIR/STEM.{csv,md,json}, the kind's extra files and the plot; returns whether it plotted.
  std::function<bool(const std::filesystem::path& dir, const Spec&, const Result&,
                     const std::string& title, const PlotOptions&, std::ostream& err)>
      write;
  std::function<void(const Spec&, const Result&, std::ostream& out)> print_summary;
  std::function<std::string(const Spec&, const Result&, const std::string& note)> report_markdown;
  std::function<std::string(const Spec&)> default_title;
  // Integrators besides the studied ones whose parameters the study consumes (optional).
  std::function<std::vector<std::string>(const Spec&)> helpers;
};

// The job of any study: its inputs, typed spec (whose to_json() is the recorded spec) and result.
template <class Spec, class Result>
class TypedStudyJob final : public StudyJob {
 public:
  TypedStudyJob(const StudyFunctions<Spec, Result>& fns, StudyInputs in, Spec spec)
      : fns_(fns), in_(std::move(in)), spec_(std::move(spec)) {}
  nlohmann::json spec_json() const override { return spec_.to_json(); }
  std::vector<std::string> helper_integrators() const override {
    return fns_.helpers ? fns_.helpers(spec_) : std::vector<std::string>{};
  }
  void run(std::ostream* progress) override { result_ = fns_.run(in_, spec_, progress); }
  Table unit_table() const override { return fns_.unit_table(spec_, result_); }
  // The plots' panels take the families of the study's own integrators (objects included).
  bool write(const std::filesystem::path& dir, const std::string& title, const PlotOptions& plot,
             std::ostream& err) const override {
    PlotOptions own = plot;
    own.family = [this](const std::string& label) { return integrator_family(in_, label); };
    return fns_.write(dir, spec_, result_, title, own, err);
  }
  void print_summary(std::ostream& out) const override { fns_.print_summary(spec_, result_, out); }
  std::string report_markdown(const std::string& note) const override {
    return fns_.report_markdown(spec_, result_, note);
  }
  std::string default_title() const override { return fns_.default_title(spec_); }
  const Spec& spec() const { return spec_; }
  const Result& result() const { return result_; }

 private:
  const StudyFunctions<Spec, Result>& fns_;  // a study's static table
  StudyInputs in_;
  Spec spec_;
  Result result_{};
};

// The result of a job of this study (std::bad_cast for another study's job).
template <class Spec, class Result>
const Result& typed_result(const StudyJob& job) {
  return dynamic_cast<const TypedStudyJob<Spec, Result>&>(job).result();
}

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
  // Builds the job from the resolved inputs and options (every declared key with a default is
  // present; an option without default is present only when given). BadInput naming the option
  // for values the declaration cannot express (combinations, lists).
  std::function<std::unique_ptr<StudyJob>(const StudyInputs&, const Params& options,
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

// Configures a job: the target resolved (resolve_inputs, relative method-file paths from
// `base`), the options resolved with `how`.
std::unique_ptr<StudyJob> make_study(const StudyKind& kind, const StudyTarget& target,
                                     const Params& options, const StudyContext& ctx,
                                     const std::function<std::string(const std::string&)>& how,
                                     const std::string& base = "");

// The pipeline of a one-off study, for the command line and for programs: checks that DIR can
// be written and holds no results of a different spec (unless ctx.force), runs the study
// (progress to ctx.progress), writes DIR/STEM.{csv,md,json} and the extra files, draws the plot
// (warnings to ctx.err), and prints the summary and the files written to ctx.out. Returns the
// job, whose result accessors the study's own header offers (e.g. convergence_result()).
std::unique_ptr<StudyJob> run_study(const std::string& kind, StudyTarget target,
                                    const Params& options, const std::filesystem::path& dir,
                                    StudyContext ctx);
// The same pipeline for a job already configured (e.g. a TypedStudyJob a program made).
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

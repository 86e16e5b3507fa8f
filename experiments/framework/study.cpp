#include "experiments/framework/study.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/integrator.hpp"
#include "core/ode_system.hpp"

namespace stiffbench {

// The built-in studies, each defined in its own file.
StudyKind convergence_study_kind();
StudyKind local_error_study_kind();
StudyKind work_precision_study_kind();
StudyKind stability_study_kind();
StudyKind region_study_kind();
StudyKind energy_study_kind();
StudyKind audit_study_kind();
StudyKind analyze_study_kind();
StudyKind fidelity_study_kind();
StudyKind budget_study_kind();
StudyKind recommend_study_kind();

namespace {

std::vector<StudyKind>& mutable_study_kinds() {
  static std::vector<StudyKind> kinds = {
      convergence_study_kind(), local_error_study_kind(), work_precision_study_kind(),
      stability_study_kind(),   region_study_kind(),      energy_study_kind(),
      audit_study_kind(),       analyze_study_kind(),     fidelity_study_kind(),
      budget_study_kind(),      recommend_study_kind()};
  return kinds;
}

const ParamSpec* find_option(const StudyKind& kind, const std::string& key) {
  for (const auto& o : kind.options)
    if (o.key == key) return &o;
  return nullptr;
}

}  // namespace

const std::vector<StudyKind>& study_kinds() { return mutable_study_kinds(); }

const StudyKind* find_study(const std::string& name) {
  for (const auto& k : study_kinds())
    if (k.name == name) return &k;
  return nullptr;
}

std::vector<std::string> study_names() {
  std::vector<std::string> names;
  for (const auto& k : study_kinds()) names.push_back(k.name);
  return names;
}

const StudyKind& study_kind(const std::string& name) {
  if (const StudyKind* k = find_study(name)) return *k;
  throw BadInput("unknown study '" + name + "'" + did_you_mean(name, study_names()) +
                 "; known: " + join(study_names()));
}

void register_study(StudyKind kind) {
  if (find_study(kind.name)) throw std::logic_error("study '" + kind.name + "' registered twice");
  if (!kind.make) throw std::logic_error("study '" + kind.name + "' has no make function");
  for (const auto& r : kind.required)
    if (!find_option(kind, r))
      throw std::logic_error("study '" + kind.name + "': required option '" + r +
                             "' is not declared");
  mutable_study_kinds().push_back(std::move(kind));
}

std::string option_flag(const std::string& key) {
  std::string flag = "--" + key;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

Params resolve_study_options(const StudyKind& kind, const Params& given,
                             const std::function<std::string(const std::string&)>& how) {
  std::vector<std::string> known;
  for (const auto& o : kind.options) known.push_back(o.key);
  Params out;
  for (const auto& o : kind.options)
    if (!o.default_value.empty()) out.set(o.key, o.default_value);
  for (const auto& [key, value] : given.values()) {
    const ParamSpec* o = find_option(kind, key);
    if (!o)
      throw BadInput(how(key) + ": not an option of " + kind.name + did_you_mean(key, known) +
                     "; its options: " + join(known));
    Params one;
    one.set(key, value);
    try {
      resolve_params({*o}, one, nullptr, kind.name);
    } catch (const BadInput& e) {
      throw BadInput(how(key) + ": " + e.what());
    }
    out.set(key, value);
  }
  for (const auto& r : kind.required)
    require_input(given.contains(r), how(r) + " is required for " + kind.name);
  return out;
}

void describe_study(const StudyKind& kind, std::ostream& out) {
  out << "study " << kind.name << ": " << kind.summary << "\n";
  out << "inputs: " << (kind.takes_model ? "--model, " : "") << "--integrators"
      << (kind.integrators_required ? "" : " (optional)") << (kind.takes_params ? ", --param" : "")
      << "\n";
  out << "writes: " << kind.stem << ".{csv,md,json,png}";
  for (const auto& f : kind.extra_files) out << ", " << f;
  out << "\nspec file: kind = \"" << kind.name << "\", keys as below (list values sweep)\n\n";
  Table t{{"option", "flag", "type", "default", "range", "meaning"}, {}};
  for (const auto& o : kind.options) {
    const bool required =
        std::find(kind.required.begin(), kind.required.end(), o.key) != kind.required.end();
    std::string range = "-";
    if (!o.choices.empty()) range = join(o.choices, " | ");
    if (o.bounds.declared()) range = o.bounds.to_string();
    t.rows.push_back({o.key, option_flag(o.key), to_string(o.type),
                      required ? "(required)" : (o.default_value.empty() ? "-" : o.default_value),
                      range, o.help});
  }
  out << t.to_markdown();
}

std::unique_ptr<StudyJob> make_study(const StudyKind& kind, const StudyTarget& target,
                                     const Params& options, const StudyContext& ctx,
                                     const std::function<std::string(const std::string&)>& how,
                                     const std::string& base) {
  if (kind.takes_model && kind.model_required)
    require_input(!target.model.empty() || target.objects.system, how("model") + " is required");
  require_input(
      kind.takes_params || target.params.empty(),
      "--param does not apply to " + kind.name + ": it depends only on the methods' coefficients");
  if (kind.integrators_required)
    require_input(!target.integrators.empty() || !target.objects.integrators.empty(),
                  "--integrators: no integrator given");
  const Params resolved = resolve_study_options(kind, options, how);
  return kind.make(resolve_inputs(target, {}, base), resolved, ctx);
}

namespace {

// An ostream that drops everything (no err stream given).
struct NullStream : std::ostream {
  NullStream() : std::ostream(nullptr) {}
};

}  // namespace

std::unique_ptr<StudyJob> run_study(const std::string& kind_name, StudyTarget target,
                                    const Params& options, const std::filesystem::path& dir,
                                    StudyContext ctx) {
  const StudyKind& kind = study_kind(kind_name);
  if (ctx.use_output_cache && ctx.cache_dir.empty()) ctx.cache_dir = dir.string();
  auto job = make_study(kind, target, options, ctx, option_flag);
  run_study_job(kind, *job, dir, ctx);
  return job;
}

void run_study_job(const StudyKind& kind, StudyJob& job_ref, const std::filesystem::path& dir,
                   const StudyContext& ctx) {
  StudyJob* job = &job_ref;
  NullStream null;
  std::ostream& err = ctx.err ? *ctx.err : null;
  require_output_dir(dir);
  // Claimed before the check: no other run writes here between the check and this one's files.
  const FolderClaim claim(dir, ctx.err);
  check_study_output(dir, kind.stem, with_method_files(job->spec_json()), ctx.force, ctx.err,
                     kind.extra_files);
  job->run(ctx.progress);
  PlotOptions plot = ctx.plot;
  if (!plot.family) plot.family = registered_family;
  const bool plotted =
      job->write(dir, ctx.title.empty() ? job->default_title() : ctx.title, plot, err);
  if (ctx.out) {
    std::ostream& out = *ctx.out;
    job->print_summary(out);
    out << "\nwrote " << (dir / kind.stem).string() << ".{csv,md,json}";
    for (std::size_t i = 0; i < kind.extra_files.size(); ++i)
      out << (i + 1 == kind.extra_files.size() ? " and " : ", ")
          << (dir / kind.extra_files[i]).string();
    out << "\n";
    if (plotted) out << "plot: " << (dir / (kind.stem + ".png")).string() << "\n";
  }
}

std::string integrator_family(const StudyInputs& in, const std::string& label) {
  const auto* e = in.find_integrator(label);
  return e ? to_string(e->info.family) : std::string();
}

std::string registered_family(const std::string& name) {
  const auto* e = integrator_registry().find(name);
  return e ? to_string(e->info.family) : std::string();
}

Resolved resolve_step(const OdeSystem& sys, double given, const std::string& model,
                      const std::function<Resolved()>& fallback) {
  if (!std::isnan(given)) return {given, "--h"};
  if (const auto suggested = sys.suggested_step())
    return {suggested->h, "suggested step: " + suggested->rule};
  if (fallback) return fallback();
  throw BadInput("--h is required: model '" + model + "' offers no suggested step");
}

Resolved resolve_end_time(const OdeSystem& sys, double given, const std::string& model) {
  if (!std::isnan(given)) return {given, "--t-end"};
  const auto literature = sys.end_time();
  require_input(literature.has_value(),
                "--t-end is required: model '" + model + "' has no literature end time");
  return {*literature, "the model's literature end time"};
}

double optional_real(const Params& options, const std::string& key) {
  return options.contains(key) ? options.real(key) : std::nan("");
}

}  // namespace stiffbench

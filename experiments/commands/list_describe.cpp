#include "experiments/commands/list_describe.hpp"
#include "experiments/framework/study.hpp"

#include <algorithm>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/framework/catalog.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

const std::vector<CommandEntry>& command_entries() {
  static const std::vector<CommandEntry> entries = {
      {"solve", "trajectory CSV (t,y0,y1,...); with --frames: VTK/CSV frames, observables.csv",
       "one run (fixed step with --h, else the model's suggested step or adaptive): final "
       "state, invariants, observables, statistics; --times/--log-outputs: the state at given "
       "times (exact stops when adaptive, nearest step when fixed); --frames writes particle "
       "frames"},
      {"run", "OUT/<kind>.csv row by row, OUT/run.json",
       "run a TOML spec file (one experiment kind; list-valued keys expand into a sweep); "
       "writes OUT/<kind>.csv row by row and OUT/run.json. Exit code 3: some unit failed (its "
       "rows record status and message)"},
      {"merge", "OUT/<kind>.csv, OUT/run.json",
       "join the folders of `run --shard` into one (rows sorted by unit); refuses folders of "
       "different specs. Exit code 3: units missing or failed"},
      {"plot", "NAME.png (and .svg) next to each CSV",
       "redraw the plots of an output folder (searched recursively) from its CSV files; needs "
       "gnuplot"},
      {"report", "DIR/REPORT.md and one folder per study",
       "run a suite of spec files (default: the built-in suite, suites/report/) and write "
       "DIR/REPORT.md with one section per spec"},
      {"profile", "DIR/profile.{csv,md,json}, profile_<tau>_<cost>.png, one run folder per problem",
       "performance and data profiles over a suite of work-precision specs (built in: stiff, "
       "mechanical; or a folder): runs or reuses DIR/<problem>/, writes DIR/profile.{csv,md,json} "
       "and plots, prints the rankings"},
      {"compare", "DIR/compare.{md,csv,json}",
       "compare two runs (output folders OLD and NEW of a study, report, profile or run): which "
       "run records differ, per row the ratios NEW/OLD of error, f_evals and counters, wall "
       "times with both intervals and a verdict; writes DIR/compare.{md,csv,json}. Exit code 1: "
       "the results differ"}};
  return entries;
}

const CommandEntry& command_entry(const std::string& name) {
  for (const auto& c : command_entries())
    if (c.name == name) return c;
  throw std::logic_error("no command entry '" + name + "'");
}

namespace {

void list_models(std::ostream& out) {
  Table t{{"model", "kind", "exact", "parameters", "description"}, {}};
  for (const auto& e : model_registry().entries()) {
    std::vector<std::string> keys;
    for (const auto& p : e.params) keys.push_back(p.key);
    t.rows.push_back({e.info.name, e.info.mechanical ? "mechanical" : "first-order",
                      e.info.exact ? "yes" : "no", join(keys, " "), e.info.description});
  }
  out << t.to_markdown();
}

// "fixed", "adaptive" or "fixed, adaptive": what a default-constructed instance supports.
std::string step_modes(const IntegratorRegistry::Entry& e) {
  const auto integ = integrator_registry().create(e.info.name, Params{});
  std::vector<std::string> modes;
  if (integ->supports_fixed_step()) modes.push_back("fixed");
  if (integ->supports_adaptive()) modes.push_back("adaptive");
  return join(modes, ", ");
}

void list_integrators(std::ostream& out) {
  Table t{
      {"integrator", "family", "kind", "order", "f evals/step", "step", "requires", "description"},
      {}};
  for (const auto& e : integrator_registry().entries()) {
    const MethodInfo& m = e.info;
    t.rows.push_back({m.name, to_string(m.family), m.kind.empty() ? "-" : m.kind,
                      m.order ? std::to_string(m.order) : "variable",
                      m.stages ? std::to_string(m.stages) : "variable", step_modes(e),
                      describe_requirements(m.requires_), m.description});
  }
  out << t.to_markdown();
}

// Every command from the two declarations: the command table above and the study registry.
Table experiments_table() {
  Table t{{"experiment", "writes", "description"}, {}};
  const auto& commands = command_entries();
  t.rows.push_back({commands.front().name, commands.front().writes, commands.front().summary});
  for (const auto& k : study_kinds()) {
    std::string writes = k.stem + ".{csv,md,json,png}";
    for (const auto& f : k.extra_files) writes += ", " + f;
    t.rows.push_back({k.name, writes, k.summary});
  }
  for (std::size_t i = 1; i < commands.size(); ++i)
    t.rows.push_back({commands[i].name, commands[i].writes, commands[i].summary});
  return t;
}

void list_experiments(std::ostream& out) { out << experiments_table().to_markdown(); }

std::string count_or_variable(int n) { return n ? std::to_string(n) : "variable"; }

void print_params(const std::vector<ParamSpec>& params, std::ostream& out) {
  if (params.empty()) {
    out << "\nParameters: none\n";
    return;
  }
  out << "\nParameters (--param key=value):\n\n";
  // The range column: what resolve_params accepts for a numeric parameter.
  Table t{{"key", "type", "default", "range", "meaning"}, {}};
  for (const auto& p : params) {
    std::string help = p.help;
    if (!p.choices.empty()) help += " (one of: " + join(p.choices, ", ") + ")";
    const bool numeric = p.type == ParamType::real || p.type == ParamType::integer;
    t.rows.push_back(
        {p.key, to_string(p.type), p.default_value, numeric ? p.bounds.to_string() : "", help});
  }
  out << t.to_markdown();
}

}  // namespace

void cmd_list(const std::string& what, std::ostream& out) {
  if (what.empty() || what == "models") {
    if (what.empty()) out << "Models:\n\n";
    list_models(out);
  }
  if (what.empty() || what == "integrators") {
    if (what.empty()) out << "\nIntegrators:\n\n";
    list_integrators(out);
  }
  if (what.empty() || what == "experiments") {
    if (what.empty()) out << "\nExperiments:\n\n";
    list_experiments(out);
  }
}

namespace {

// The model's additive splits (OdeSystem::imex_split): each value of its `split` parameter with
// what each part holds, the default marked; "none" when the model has no split.
void describe_splits(const std::string& name, const std::vector<ParamSpec>& params,
                     const OdeSystem& defaults, std::ostream& out) {
  const auto spec = std::find_if(params.begin(), params.end(),
                                 [](const ParamSpec& p) { return p.key == "split"; });
  if (spec == params.end()) {
    const auto info = defaults.imex_split();
    out << "splits: "
        << (info ? info->name
            : defaults.has_imex_split()
                ? std::string("one (unnamed: the model does not describe it)")
                : std::string("none"))
        << "\n";
    if (info)
      out << "  " << info->name << ": explicit f_E = " << info->explicit_part
          << "; implicit f_I = " << info->implicit_part << "\n";
    return;
  }
  out << "splits (parameter split, default " << spec->default_value << "):\n";
  for (const std::string& value : spec->choices) {
    const auto sys = model_registry().create(name, Params{{"split", value}});
    const auto info = sys->imex_split();
    out << "  " << value << ": ";
    if (info)
      out << "explicit f_E = " << info->explicit_part << "; implicit f_I = " << info->implicit_part
          << "\n";
    else
      out << "no split (f is not divided)\n";
  }
}

}  // namespace

void cmd_describe(const std::string& name, std::ostream& out) {
  if (const auto* m = model_registry().find(name)) {
    out << "model " << name << ": " << m->info.description << "\n";
    out << "kind: " << (m->info.mechanical ? "mechanical (y = [x; v])" : "first-order") << "\n";
    out << "exact solution: " << (m->info.exact ? "yes" : "no") << "\n";
    out << "source: " << m->info.source << "\n";
    const auto sys = model_registry().create(name, Params{});
    out << "dimension (defaults): " << sys->dimension() << "\n";
    std::vector<std::string> inv;
    for (const auto& i : sys->invariants()) inv.push_back(i.name);
    out << "invariants: " << (inv.empty() ? "none" : join(inv)) << "\n";
    out << "analytic Jacobian: " << (sys->has_jacobian() ? "yes" : "no") << "\n";
    if (const auto s = sys->suggested_step())
      out << "suggested step (defaults): " << format_short(s->h, 4) << " (" << s->rule << ")\n";
    std::vector<std::string> obs;
    for (const auto& o : sys->observables()) obs.push_back(o.name);
    if (!obs.empty()) out << "observables: " << join(obs) << "\n";
    if (!m->info.rest_state.empty()) {
      std::vector<std::string> rest;
      for (const auto& [k, v] : m->info.rest_state) rest.push_back(k + "=" + v);
      out << "rest state (fidelity's modes; applied where not given): " << join(rest) << "\n";
    }
    describe_splits(name, m->params, *sys, out);
    print_params(m->params, out);
    return;
  }
  if (const auto* e = integrator_registry().find(name)) {
    const MethodInfo& i = e->info;
    out << "integrator " << name << ": " << i.description << "\n";
    out << "family: " << to_string(i.family);
    if (!i.kind.empty()) out << " (" << i.kind << ")";
    out << "\nreference: " << (i.reference.empty() ? "none given" : i.reference);
    if (const std::string file = method_file_source(name); !file.empty())
      out << "\nsource: " << file;
    out << "\nstep: " << step_modes(*e) << "\norder: " << count_or_variable(i.order)
        << "\nevaluations per step: " << count_or_variable(i.stages)
        << "\nrequires: " << describe_requirements(i.requires_) << "\n";
    print_params(e->params, out);
    return;
  }
  if (const StudyKind* k = find_study(name)) {
    describe_study(*k, out);
    out << "\nflags: stiffbench " << name << " --help\n";
    return;
  }
  std::vector<std::string> experiments;
  for (const auto& row : experiments_table().rows) {
    experiments.push_back(row[0]);
    if (row[0] != name) continue;
    out << "experiment " << name << ": " << row[2] << "\n";
    out << "writes: " << row[1] << "\n";
    out << "flags: stiffbench " << name << " --help\n";
    return;
  }
  std::vector<std::string> all = model_registry().names();
  for (const auto& n : integrator_registry().names()) all.push_back(n);
  for (const auto& n : experiments) all.push_back(n);
  throw BadInput("unknown name '" + name + "'" + did_you_mean(name, all) + ": not a model (" +
                 join(model_registry().names()) + "), an integrator (" +
                 join(integrator_registry().names()) + ") nor an experiment (" + join(experiments) +
                 ")");
}

}  // namespace stiffbench

#include "experiments/commands/list_describe.hpp"
#include "experiments/framework/study.hpp"

#include <algorithm>
#include <ostream>
#include <string>
#include <vector>

#include "experiments/framework/catalog.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

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

Table experiments_table() {
  Table t{{"experiment", "writes", "description"}, {}};
  t.rows.push_back({"solve",
                    "trajectory CSV (t,y0,y1,...); with --frames: VTK/CSV frames, observables.csv",
                    "one run (fixed step, the model's suggested step, or adaptive); final state, "
                    "invariants, observables and statistics; --times/--log-outputs: the state at "
                    "given times (exact stops when adaptive, nearest step when fixed)"});
  t.rows.push_back({"convergence", "convergence.{csv,md,json,png}; reference/<hash>.csv",
                    "global error at t_end vs h, observed orders; a non-exact reference is "
                    "cached in the output folder"});
  t.rows.push_back(
      {"local-error", "local_error.{csv,md,json,png}", "error of one step vs h, observed slopes"});
  t.rows.push_back({"work-precision", "work_precision.{csv,md,json,png}",
                    "error at t_end against work: h ladder for fixed-step methods, tolerance "
                    "ladder for references"});
  t.rows.push_back({"stability", "stability.{csv,md,json,png}",
                    "largest stable fixed step per integrator (bisection) against linear theory; "
                    "--sweep over a stiffness parameter with log-log slope"});
  t.rows.push_back({"region", "region.{csv,md,json,png}, region_limits.csv",
                    "stability region boundaries (amplification 1) from the coefficients, axis and "
                    "oscillator limits, A-stability"});
  t.rows.push_back({"analyze",
                    "analyze.{csv,md,json,png}, analyze_conditions.csv, analyze_dispersion.csv",
                    "what the coefficients say, nothing run: order conditions to order 8, stage "
                    "and embedded order, error norms, R = P/Q, A-/L-stability, exact axis limits, "
                    "internal stability, SSP coefficient, dissipation and dispersion"});
  t.rows.push_back({"energy", "energy.{csv,md,json,png}, energy_summary.csv",
                    "relative invariant error at every step, sampled; max, final, drift rate, "
                    "growth ratio"});
  t.rows.push_back({"plot", "NAME.png (and .svg) next to each CSV",
                    "redraw the plots of an output folder from its CSV files"});
  t.rows.push_back({"report", "DIR/REPORT.md and one folder per study",
                    "the default suite: convergence, local error, energy drift, stability "
                    "limits and regions, work-precision"});
  t.rows.push_back(
      {"profile", "DIR/profile.{csv,md,json}, profile_<tau>_<cost>.png, one run folder per problem",
       "performance and data profiles over a suite of work-precision specs (stiff, "
       "mechanical or a folder) at each --tau and --cost, rankings"});
  t.rows.push_back({"compare", "DIR/compare.{md,csv,json}",
                    "two runs of the same study, report or profile: which specs, revisions, "
                    "compilers, CPUs and versions differ; per row the error, f_evals and counter "
                    "ratios and wall times with a verdict; exit 1 when results differ"});
  // Studies registered from outside the library (register_study).
  for (const auto& k : study_kinds()) {
    bool listed = false;
    for (const auto& row : t.rows) listed = listed || row[0] == k.name;
    if (!listed) t.rows.push_back({k.name, k.stem + ".{csv,md,json,png}", k.summary});
  }
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

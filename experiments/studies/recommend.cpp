#include "experiments/studies/recommend.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "core/run_control.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/support/reference.hpp"
#include "experiments/support/timing.hpp"

namespace stiffbench {

namespace {

constexpr const char* kBudgetKey = "budget";
const double kNaN = std::numeric_limits<double>::quiet_NaN();

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void RecommendSpec::validate() const {
  require_input(std::isfinite(rtol) && rtol > 0 && rtol < 1,
                "--rtol must be in (0, 1) (got " + format_full(rtol) + ")");
  require_input(std::isfinite(budget_s) && budget_s > 0,
                "--budget must be > 0 seconds (got " + format_full(budget_s) + ")");
  require_input(std::isfinite(t_end) && t_end >= 0,
                "--t-end must be >= 0 (0: the model's end time; got " + format_full(t_end) + ")");
  require_input(timing_repeats >= 1, option_flag(timing_repeats_option("").key) + " must be >= 1");
}

nlohmann::json RecommendSpec::to_json() const {
  nlohmann::json j;
  j["model"] = model;
  j["params"] = params.values();
  j["integrators"] = integrators;
  j["rtol"] = rtol;
  j["t_end"] = t_end;
  j[kBudgetKey] = budget_s;
  j[timing_repeats_option("").key] = timing_repeats;
  j["seed"] = seed;
  return j;
}

namespace {

// Which families the model's capabilities call for (see the header comment), and why.
struct FamilyChoice {
  bool stiff = false, mechanical = false, small = false;
  std::string note;
};

FamilyChoice choose_families(const OdeSystem& sys, double t_end) {
  FamilyChoice c;
  c.mechanical = sys.as_mechanical() != nullptr;
  c.small = sys.dimension() <= kSmallDimension;
  const double t0 = sys.initial_time();
  const auto rho = sys.stiffness(t0, sys.initial_state());
  std::ostringstream note;
  if (rho) {
    const double ratio = *rho * (t_end - t0);
    c.stiff = ratio >= kStiffRatio;
    note << "stiffness estimate rho = " << format_short(*rho)
         << " at t0, rho*(t_end - t0) = " << format_short(ratio) << (c.stiff ? " >= " : " < ")
         << format_short(kStiffRatio) << ": " << (c.stiff ? "stiff" : "not stiff");
  } else {
    c.stiff = c.mechanical && sys.has_jacobian();
    note << "no stiffness estimate; "
         << (c.stiff ? "mechanical with force Jacobians: treated as stiff"
                     : "treated as not stiff");
  }
  note << "; dimension " << sys.dimension() << (c.mechanical ? ", mechanical" : "");
  c.note = note.str();
  return c;
}

// Whether the family suits the model, and why (not).
std::pair<bool, std::string> family_fits(Family f, const FamilyChoice& c) {
  switch (f) {
    case Family::explicit_rk:
      if (c.stiff) return {false, "explicit: the model is stiff (h limited by ~3/rho)"};
      return {true, "explicit: the model is not stiff"};
    case Family::symplectic:
    case Family::graphics:
      if (c.mechanical) return {true, to_string(f) + ": mechanical model"};
      return {false, to_string(f) + ": needs a mechanical model"};
    default:  // implicit, the library methods, imex, splitting
      if (c.stiff) return {true, to_string(f) + ": the model is stiff"};
      if (c.small) return {true, to_string(f) + ": not stiff, but the model is small"};
      return {false, to_string(f) + ": not stiff and large: explicit methods are cheaper"};
  }
}

std::vector<RecommendCandidate> choose_candidates(const StudyInputs& in, const RecommendSpec& spec,
                                                  const OdeSystem& sys, const FamilyChoice& c) {
  std::vector<std::string> names = integrator_registry().names();
  for (const auto& n : spec.integrators)
    if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  std::vector<RecommendCandidate> out;
  for (const auto& name : names) {
    const MethodInfo& info = in.integrator_entry(name).info;
    RecommendCandidate cand{name, to_string(info.family), false, ""};
    try {
      check_compatible(info, sys);
    } catch (const BadInput& e) {
      cand.reason = std::string("incompatible: ") + e.what();
      out.push_back(cand);
      continue;
    }
    const bool own =
        std::find(spec.integrators.begin(), spec.integrators.end(), name) != spec.integrators.end();
    auto [fits, why] = family_fits(info.family, c);
    cand.included = fits || own;
    cand.reason = own && !fits ? "given by the caller (" + why + ")" : why;
    out.push_back(cand);
  }
  return out;
}

bool takes_rtol(const StudyInputs& in, const std::string& name) {
  for (const auto& p : in.integrator_entry(name).params)
    if (p.key == "rtol") return true;
  return false;
}

// The settings of a method: a tolerance ladder around R, or a step ladder from h0.
std::vector<double> settings_of(bool adaptive, double rtol, double h0) {
  if (adaptive) return {rtol * 10, rtol, rtol / 10, rtol / 100};
  std::vector<double> hs;
  for (int k = 0; k < kFixedLevels; ++k) hs.push_back(h0 / std::pow(4.0, k));
  return hs;
}

struct SweepState {
  const StudyInputs& in;
  const RecommendSpec& spec;
  const OdeSystem& sys;
  const Vec& ref;
  double t_end, h0, ref_norm;
  std::chrono::steady_clock::time_point start;
  std::ostream* progress;
};

// Runs one method's ladder within `share` seconds; appends its rows; returns why it stopped
// without meeting R ("" when it met R).
std::string sweep_method(const SweepState& s, const RecommendCandidate& cand, double share,
                         std::vector<RecommendRow>& rows) {
  const auto probe = s.in.create_integrator(cand.integrator, s.spec.params);
  const bool adaptive = probe->supports_adaptive() && takes_rtol(s.in, cand.integrator);
  if (!adaptive && !probe->supports_fixed_step()) return "no fixed-step mode and no rtol";
  const auto method_start = std::chrono::steady_clock::now();
  std::string last;
  double best = kNaN;
  for (double setting : settings_of(adaptive, s.spec.rtol, s.h0)) {
    const double left = share - seconds_since(method_start);
    if (left <= 0) return "its share of the budget (" + format_short(share, 2) + " s) was spent";
    if (!adaptive && (s.t_end - s.sys.initial_time()) / setting >
                         static_cast<double>(FixedStepOptions{}.max_steps))
      break;
    RecommendRow row;
    row.run = run_work_precision_setting(s.in, s.sys, s.spec.model, cand.integrator, s.spec.params,
                                         adaptive, setting, kRecommendAtolRatio, s.t_end, s.ref,
                                         s.spec.timing_repeats, s.spec.seed, rows.size(), left);
    row.family = cand.family;
    const bool ok = row.run.stats.status == Status::ok;
    row.error_rel = ok ? row.run.error / std::max(1.0, s.ref_norm) : kNaN;
    row.meets = ok && row.error_rel <= s.spec.rtol;
    if (s.progress)
      *s.progress << "  " << cand.integrator << " " << row.run.setting << ": "
                  << (ok ? "error_rel " + format_short(row.error_rel)
                         : to_string(row.run.stats.status))
                  << ", f_evals " << row.run.stats.f_evals << ", "
                  << format_short(row.run.wall.median, 2) << " s\n"
                  << std::flush;
    const Status st = row.run.stats.status;
    const bool meets = row.meets;
    if (ok && !(best <= row.error_rel)) best = row.error_rel;
    rows.push_back(std::move(row));
    if (meets) return "";
    if (st == Status::timeout) return "timeout (a setting passed its share of the budget)";
    if (st != Status::ok) last = to_string(st);
    if (adaptive && st != Status::ok) return "failed (" + last + ")";
  }
  if (!std::isnan(best)) return "never reached R (best error_rel " + format_short(best) + ")";
  return last == "unstable" ? "unstable at every step tried" : "failed (" + last + ")";
}

void choose_answer(RecommendResult& r) {
  const auto cheaper_wall = [&](std::size_t a, std::size_t b) {
    return r.rows[a].run.wall.median < r.rows[b].run.wall.median;
  };
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    if (!r.rows[i].meets) continue;
    if (!r.best_wall || cheaper_wall(i, *r.best_wall)) r.best_wall = i;
    const long f = r.rows[i].run.stats.f_evals;
    if (!r.best_f || f < r.rows[*r.best_f].run.stats.f_evals ||
        (f == r.rows[*r.best_f].run.stats.f_evals && cheaper_wall(i, *r.best_f)))
      r.best_f = i;
    bool placed = false;
    for (auto& k : r.ranked)
      if (r.rows[k].run.integrator == r.rows[i].run.integrator) {
        if (cheaper_wall(i, k)) k = i;
        placed = true;
      }
    if (!placed) r.ranked.push_back(i);
  }
  std::sort(r.ranked.begin(), r.ranked.end(), cheaper_wall);
}

}  // namespace

void mark_pareto(std::vector<RecommendRow>& rows) {
  const auto ok = [](const RecommendRow& r) { return r.run.stats.status == Status::ok; };
  for (auto& a : rows) {
    a.pareto_wall = a.pareto_f = ok(a);
    if (!ok(a)) continue;
    for (const auto& b : rows) {
      if (&a == &b || !ok(b)) continue;
      const double ea = a.error_rel, eb = b.error_rel;
      const double wa = a.run.wall.median, wb = b.run.wall.median;
      const long fa = a.run.stats.f_evals, fb = b.run.stats.f_evals;
      if (eb <= ea && wb <= wa && (eb < ea || wb < wa)) a.pareto_wall = false;
      if (eb <= ea && fb <= fa && (eb < ea || fb < fa)) a.pareto_f = false;
    }
  }
}

RecommendResult run_recommend(const StudyInputs& in, const RecommendSpec& spec_in,
                              std::ostream* progress) {
  const auto start = std::chrono::steady_clock::now();
  const RecommendSpec spec = with_inputs(spec_in, in);
  spec.validate();
  Setup with_params = make_setup(in, {}, spec.params);
  const OdeSystem& sys = *with_params.model;
  RecommendResult r;
  r.model = spec.model;
  r.rtol = spec.rtol;
  r.budget_s = spec.budget_s;
  r.dimension = static_cast<long>(sys.dimension());
  const double t0 = sys.initial_time();
  const bool scene = sys.as_mechanical() != nullptr && !sys.end_time();
  r.t_end = spec.t_end > 0 ? spec.t_end
            : scene        ? kSceneEndTime
                           : resolve_end_time(sys, std::nan(""), spec.model).value;
  require_input(r.t_end > t0, "--t-end must be > the model's initial time");
  const Resolved h0 = resolve_step(sys, std::nan(""), spec.model, [&] {
    return Resolved{(r.t_end - t0) / 100, "(t_end - t0)/100"};
  });
  r.h0 = h0.value;
  r.h0_source = h0.source;
  const FamilyChoice fc = choose_families(sys, r.t_end);
  r.stiff = fc.stiff;
  r.mechanical = fc.mechanical;
  r.stiffness_note = fc.note;
  r.candidates = choose_candidates(in, spec, sys, fc);
  if (progress) *progress << fc.note << "\n";

  // The exact solution, else an adaptive run (see the header comment).
  const bool exact = sys.has_exact();
  const double ref_rtol = std::max(1e-14, spec.rtol * 1e-4);
  Vec ref;
  {
    const RowClock clock(spec.budget_s / 2);
    const ReferenceRequest req{&in,
                               spec.model,
                               spec.params,
                               exact ? "auto" : (fc.stiff ? "cvode_bdf" : "cvode_adams"),
                               exact ? std::nullopt : std::optional<double>(ref_rtol),
                               exact ? std::nullopt : std::optional<double>(ref_rtol / 100),
                               ""};
    ref = reference_at_end(req, sys, r.t_end, r.t_end, &r.reference_description);
  }
  r.ref_norm = ref.lpNorm<Eigen::Infinity>();
  if (progress)
    *progress << "reference: " << r.reference_description << " ("
              << format_short(seconds_since(start), 2) << " s)\n";

  const SweepState s{in, spec, sys, ref, r.t_end, r.h0, r.ref_norm, start, progress};
  std::vector<const RecommendCandidate*> run;
  for (const auto& c : r.candidates)
    if (c.included) run.push_back(&c);
  // A setting cut short by its share of the budget is dropped with its reason, not a fault.
  const ExpectedTimeouts planned;
  for (std::size_t i = 0; i < run.size(); ++i) {
    const double left = spec.budget_s * 0.95 - seconds_since(start);
    if (left <= 0) {
      r.dropped.emplace_back(run[i]->integrator, "not run: the budget was spent");
      continue;
    }
    const double share = left / static_cast<double>(run.size() - i);
    if (progress)
      *progress << "[" << i + 1 << "/" << run.size() << "] " << run[i]->integrator << "\n";
    const std::string why = sweep_method(s, *run[i], share, r.rows);
    if (!why.empty()) r.dropped.emplace_back(run[i]->integrator, why);
  }
  mark_pareto(r.rows);
  choose_answer(r);
  r.total_wall_s = seconds_since(start);
  return r;
}

Table recommend_table(const RecommendResult& r) {
  // The first five columns and wall_s (9) where work_precision.csv has them; plots/recommend.gp
  // reads columns 2, 7, 9 and 11.
  Table t{{"model", "integrator", "setting", "error", "f_evals", "family", "error_rel", "status",
           "wall_s", "meets_rtol", "on_pareto_wall", "on_pareto_f"},
          {}};
  for (const auto& row : r.rows) {
    const bool ok = row.run.stats.status == Status::ok;
    t.rows.push_back(
        {r.model, row.run.integrator, row.run.setting, ok ? format_full(row.run.error) : "",
         std::to_string(row.run.stats.f_evals), row.family, ok ? format_full(row.error_rel) : "",
         to_string(row.run.stats.status), format_full(row.run.wall.median), row.meets ? "1" : "0",
         row.pareto_wall ? "1" : "0", row.pareto_f ? "1" : "0"});
  }
  return t;
}

namespace {

std::string row_line(const RecommendRow& row) {
  return row.run.integrator + " at " + row.run.setting + " (error_rel " +
         format_short(row.error_rel) + ", " + std::to_string(row.run.stats.f_evals) +
         " f evaluations, " + format_short(row.run.wall.median, 3) + " s)";
}

}  // namespace

std::string recommend_markdown(const RecommendResult& r) {
  std::ostringstream md;
  md << "# Recommend: " << r.model << " at rtol " << format_short(r.rtol) << "\n\n"
     << "Meets the tolerance: error_rel = ||y - y_ref||_inf / max(1, ||y_ref||_inf) <= "
     << format_short(r.rtol) << " at t_end = " << format_full(r.t_end)
     << " (||y_ref||_inf = " << format_short(r.ref_norm) << "); y_ref: " << r.reference_description
     << ". Wall time: the median over the repeats of a setting.\n\n";
  md << "## Answer\n\n";
  if (r.best_wall) md << "- Cheapest by wall time: " << row_line(r.rows[*r.best_wall]) << "\n";
  if (r.best_f) md << "- Cheapest by f evaluations: " << row_line(r.rows[*r.best_f]) << "\n";
  if (!r.best_wall) md << "- No method met the tolerance within the budget.\n";
  md << "\nRanked (each method's cheapest setting that meets the tolerance, by wall time):\n\n";
  int k = 0;
  for (std::size_t i : r.ranked) md << ++k << ". " << row_line(r.rows[i]) << "\n";
  md << "\nDropped:\n\n";
  for (const auto& [name, why] : r.dropped) md << "- " << name << ": " << why << "\n";
  md << "\n## Candidates\n\n"
     << r.stiffness_note << ". Fixed-step ladder from h0 = " << format_full(r.h0) << " ("
     << r.h0_source << "), factor 4.\n\n";
  Table c{{"integrator", "family", "considered", "why"}, {}};
  for (const auto& cand : r.candidates)
    c.rows.push_back({cand.integrator, cand.family, cand.included ? "yes" : "no", cand.reason});
  md << c.to_markdown() << "\nTotal wall time: " << format_short(r.total_wall_s, 3) << " s (budget "
     << format_short(r.budget_s, 3) << " s). Every run: `recommend.csv`.\n";
  return md.str();
}

namespace {

bool write_recommend(const std::filesystem::path& dir, const RecommendSpec& spec,
                     const RecommendResult& result, const std::string& title,
                     const PlotOptions& plot, std::ostream& err) {
  write_file_atomic(dir / "recommend.csv", recommend_table(result).to_csv());
  write_file_atomic(dir / "recommend.md", recommend_markdown(result));
  nlohmann::json meta = run_metadata("recommend", spec.to_json());
  meta["y_ref"] = result.reference_description;
  meta["t_end_used"] = result.t_end;
  meta["total_wall_s"] = result.total_wall_s;
  meta["meets_definition"] = "||y - y_ref||_inf / max(1, ||y_ref||_inf) <= rtol at t_end";
  write_file_atomic(dir / "recommend.json", meta.dump(2) + "\n");
  std::vector<std::string> methods;
  for (const auto& row : result.rows)
    if (std::find(methods.begin(), methods.end(), row.run.integrator) == methods.end())
      methods.push_back(row.run.integrator);
  return run_plot("recommend.gp", dir / "recommend",
                  {{"csvfile", (dir / "recommend.csv").string()},
                   {"ttl", title},
                   {"log10_rtol", std::to_string(std::log10(spec.rtol))}},
                  {PlotPanel{"all methods", methods}}, plot, err);
}

const StudyFunctions<RecommendSpec, RecommendResult> kRecommend{
    .run = [](const StudyInputs& in, const RecommendSpec& s,
              std::ostream* progress) { return run_recommend(in, s, progress); },
    .unit_table = [](const RecommendSpec&, const RecommendResult& r) { return recommend_table(r); },
    .write = write_recommend,
    .print_summary =
        [](const RecommendSpec& s, const RecommendResult& r, std::ostream& out) {
          const std::string md = recommend_markdown(r);
          out << md.substr(0, md.find("\n## Candidates"))
              << "\nTotal wall time: " << format_short(r.total_wall_s, 3) << " s (budget "
              << format_short(s.budget_s, 3) << " s)\n";
        },
    .report_markdown =
        [](const RecommendSpec&, const RecommendResult& r, const std::string& note) {
          return note + "\n\n" + recommend_markdown(r);
        },
    .default_title = [](const RecommendSpec& s) { return "Recommend: " + s.model; },
    .helpers = {}};

using RecommendJob = TypedStudyJob<RecommendSpec, RecommendResult>;

}  // namespace

StudyKind recommend_study_kind() {
  using P = ParamType;
  StudyKind k;
  k.name = "recommend";
  k.stem = "recommend";
  k.summary =
      "which integrator at a tolerance: a quick work-precision sweep of the suitable methods "
      "within a time budget, Pareto fronts and the cheapest methods that meet rtol; writes "
      "recommend.{csv,md,json,png}";
  k.integrators_required = false;
  k.integrators_help =
      "comma-separated integrator names or method-file paths ADDED to the candidates (every "
      "registered integrator the model suits is always considered; these run even when their "
      "family would be dropped)";
  k.options = {
      {"rtol", P::real, "", "the requested tolerance R (error_rel <= R)", Bounds::positive()},
      {"t_end", P::real, "0",
       "final time (0: the model's literature end time, else 1 s for a mechanical scene)",
       Bounds::non_negative()},
      {kBudgetKey, P::real, "60", "wall-time budget of the whole command in s", Bounds::positive()},
      timing_repeats_option("3"),
      {"seed", P::integer, "1", "seed of the bootstrap", Bounds::non_negative()}};
  k.required = {"rtol"};
  k.unit_columns = recommend_table(RecommendResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    RecommendSpec spec = with_inputs(RecommendSpec{}, t);
    spec.rtol = o.real("rtol");
    spec.budget_s = o.real(kBudgetKey);
    spec.t_end = o.real("t_end");
    spec.timing_repeats = static_cast<int>(o.integer(timing_repeats_option("").key));
    spec.seed = static_cast<unsigned long>(o.integer("seed"));
    spec.validate();
    return std::make_unique<RecommendJob>(kRecommend, t, std::move(spec));
  };
  return k;
}

const RecommendResult& recommend_result(const StudyJob& job) {
  return typed_result<RecommendSpec, RecommendResult>(job);
}

RecommendResult run_recommend(const RecommendSpec& spec, std::ostream* progress) {
  return run_recommend(inputs_of(spec), spec, progress);
}

RecommendResult recommend_study(const StudyInputs& in, RecommendSpec spec,
                                const std::filesystem::path& dir, const StudyContext& ctx) {
  spec = with_inputs(std::move(spec), in);
  spec.validate();
  RecommendJob job(kRecommend, in, std::move(spec));
  run_study_job(study_kind("recommend"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench

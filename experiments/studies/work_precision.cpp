#include "experiments/studies/work_precision.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "core/driver.hpp"
#include "core/run_control.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/support/timed_settings.hpp"

namespace stiffbench {

namespace {

// The declared defaults of the step ladder and the numerical reference (cvode_bdf at rtol
// 1e-14, atol 1e-16).
StepStudyDefaults work_precision_defaults() {
  StepStudyDefaults d;
  d.t_end_help = "final time (default: the model's literature end time)";
  d.h_help =
      "coarsest step of fixed-step methods (default: the model's suggested step, else "
      "(t_end - t0)/16000)";
  d.ladder_levels = "4";
  d.ref_rtol = "1e-14";
  d.ref_atol = "1e-16";
  d.ref_help =
      "auto | exact | published | METHOD (not one of --integrators); auto: the exact solution, "
      "else the model's published solution at t_end, else cvode_bdf; its error is estimated by "
      "a second, tighter run";
  return d;
}

}  // namespace

WorkPrecisionSpec::WorkPrecisionSpec() {
  t_end = 0;
  h = 0;
  apply_defaults(work_precision_defaults());
}

void WorkPrecisionSpec::read_options(const Params& o) {
  read_step_study_options(o, *this);
  if (std::isnan(h)) h = 0;
  tol_levels = static_cast<int>(o.integer("tol_levels"));
  rtol_max = o.real("rtol_max");
  atol_factor = o.real("atol_factor");
  repeats = static_cast<int>(o.integer(timing_repeats_option("").key));
  seed = static_cast<unsigned long>(o.integer("seed"));
}

void WorkPrecisionSpec::validate() const {
  validate_step_study();
  // The names: an unknown or a studied method.
  choose_reference(reference_request(nullptr), integrators, nullptr, 0, 0);
}

nlohmann::json WorkPrecisionSpec::to_json() const {
  nlohmann::json j = step_study_json();
  j["tol_levels"] = tol_levels;
  j["rtol_max"] = rtol_max;
  j["atol_factor"] = atol_factor;
  j[timing_repeats_option("").key] = repeats;
  j["seed"] = seed;
  return j;
}

double published_accuracy(const OdeSystem::PublishedSolution& p) {
  double acc = 0;
  for (Index i = 0; i < p.y.size(); ++i) {
    const double a = std::abs(p.y[i]);
    if (a == 0) continue;
    const double last = std::pow(10.0, std::floor(std::log10(a)) - (kPublishedDigits - 1));
    acc = std::max(acc, 0.5 * last + kUnitRoundoff * a);
  }
  return acc;
}

namespace {

// The numerical reference R and its check run R2 (tighter by kReferenceTightening) into `r`.
// `check_only`: R is the published solution's check, so a failed run is recorded, not thrown.
void numerical_reference(const ReferenceChoice& choice, const OdeSystem& sys, double t_end,
                         double h_fine, bool check_only, WorkPrecisionReference& r,
                         const std::vector<std::string>& integrators, std::ostream* progress) {
  for (const auto& integ : integrators)
    r.method_studied = r.method_studied || integ == choice.method;
  try {
    r.numerical_values =
        reference_at_end(choice.numerical, sys, t_end, h_fine, &r.numerical_description);
  } catch (const BadInput&) {
    throw;
  } catch (const std::runtime_error& e) {
    if (!check_only) throw;
    r.numerical_failure = e.what();
    r.numerical_description = choice.method + " (failed: " + r.numerical_failure + ")";
    return;
  }
  if (progress) *progress << "numerical reference: " << r.numerical_description << "\n";
  try {
    const Vec r2 = reference_at_end(choice.check, sys, t_end, h_fine * choice.check_h_factor,
                                    &r.check_description);
    if (!choice.check_description.empty()) r.check_description = choice.check_description;
    r.numerical_check = max_abs_diff(r.numerical_values, r2);
    if (progress)
      *progress << "reference check: " << r.check_description << ", difference "
                << format_short(*r.numerical_check) << "\n";
  } catch (const BadInput&) {
    throw;
  } catch (const std::runtime_error& e) {
    r.check_failure = e.what();
    if (progress) *progress << "reference check: " << e.what() << "\n";
  }
}

}  // namespace

WorkPrecisionReference work_precision_reference(const StudyInputs& in,
                                                const WorkPrecisionSpec& spec, const OdeSystem& sys,
                                                double h_fine, std::ostream* progress) {
  const ReferenceChoice choice =
      choose_reference(spec.reference_request(&in), spec.integrators, &sys, spec.t_end, h_fine);
  WorkPrecisionReference r;
  if (choice.kind == "exact") {
    r.values = reference_at_end(choice.numerical, sys, spec.t_end, h_fine, &r.description);
    r.kind = "exact";
    r.error_estimate = 0;
    r.error_source = "the exact solution";
    return r;
  }
  const auto pub = sys.published_solution();
  r.has_published = pub && std::abs(spec.t_end - pub->t) <= 1e-12 * std::abs(pub->t);
  const bool check_only = r.has_published && choice.kind != "method";
  numerical_reference(choice, sys, spec.t_end, h_fine, check_only, r, spec.integrators, progress);
  if (r.has_published) {
    r.published_t = pub->t;
    r.published_source = pub->source;
    r.published_values = pub->y;
    r.published_accuracy = published_accuracy(*pub);
    if (r.numerical_failure.empty())
      r.published_distance = max_abs_diff(r.numerical_values, pub->y);
  }
  // The numerical reference's estimated error: the larger of its check and its distance from
  // the published solution, where known.
  std::optional<double> num_error;
  std::string num_source;
  if (r.numerical_check) {
    num_error = *r.numerical_check;
    num_source = "difference from a second run, " + r.check_description;
  }
  if (r.published_distance && (!num_error || *r.published_distance > *num_error)) {
    num_error = *r.published_distance;
    num_source = "distance from the published solution (" + r.published_source + ")";
  }
  const bool use_published =
      choice.kind == "published" || (choice.kind == "auto" && r.has_published &&
                                     (!num_error || r.published_accuracy < *num_error));
  if (use_published) {
    r.kind = "published";
    r.values = r.published_values;
    r.description =
        "published solution at t = " + format_full(r.published_t) + " (" + r.published_source + ")";
    r.error_estimate = r.published_accuracy;
    r.error_source = "stated accuracy of the published values (" +
                     std::to_string(kPublishedDigits) + " significant digits)";
    return r;
  }
  r.kind = "numerical";
  r.values = r.numerical_values;
  r.description = r.numerical_description;
  r.error_estimate = num_error;
  r.error_source =
      num_error ? num_source : "not estimated: the check run failed (" + r.check_failure + ")";
  return r;
}

namespace {

// An adaptive method runs over the tolerance ladder, so it must take rtol and atol (a user's
// integrator object without them would run at its own tolerance in every row).
void require_tolerance_params(const StudyInputs& in, const Setup& setup) {
  for (std::size_t i = 0; i < setup.integrators.size(); ++i) {
    const auto& integ = setup.integrators[i];
    if (!integ->supports_adaptive()) continue;
    const auto& entry = in.integrator_entry(in.integrators[i]);
    bool tolerances = false;
    for (const auto& p : entry.params) tolerances = tolerances || p.key == "rtol";
    require_input(tolerances, "integrator '" + integ->info().name +
                                  "' is adaptive but takes no rtol/atol parameters: "
                                  "work-precision cannot run it over a tolerance ladder "
                                  "(register it with rtol and atol, or give it a fixed-step mode)");
  }
}

}  // namespace

WorkPrecisionResult run_work_precision(const StudyInputs& in, const WorkPrecisionSpec& s,
                                       std::ostream* progress) {
  WorkPrecisionSpec spec = with_inputs(s, in);
  spec.validate();
  require_input(spec.tol_levels >= 2,
                "--tol-levels must be >= 2 (got " + std::to_string(spec.tol_levels) + ")");
  require_input(spec.max_runs() >= 1, option_flag(timing_repeats_option("").key) + " must be >= 1");
  require_input(spec.rtol_max > 0 && spec.rtol_max < 1, "--rtol-max must be in (0, 1)");
  require_input(spec.atol_factor >= 0, "--atol-factor must be >= 0");
  Setup setup = make_setup(in);
  const OdeSystem& sys = *setup.model;
  const double t0 = sys.initial_time();
  spec.t_end = resolve_end_time(sys, spec.t_end == 0 ? std::nan("") : spec.t_end, spec.model).value;
  require_input(spec.t_end > t0, "--t-end must be > the model's initial time");
  // exact / published: the model has it.
  choose_reference(spec.reference_request(&in), spec.integrators, &sys, spec.t_end, 0);
  const Resolved h0 = resolve_step(sys, spec.h == 0 ? std::nan("") : spec.h, spec.model, [&] {
    return Resolved{(spec.t_end - t0) / 16000, "(t_end - t0)/16000"};
  });
  if (progress && h0.source != "--h")
    *progress << "coarsest h = " << format_full(h0.value) << " (" << h0.source << ")\n";
  spec.h = h0.value;
  const std::string h_source = h0.source;
  require_input(spec.h > 0, "--h must be > 0");
  std::vector<double> tols;
  const std::vector<double> hs = spec.step_ladder(spec.h);
  for (int k = 0; k < spec.tol_levels; ++k) tols.push_back(spec.rtol_max / std::pow(10.0, k));
  for (double h : hs) fixed_step_count(t0, spec.t_end, h, FixedStepOptions{}.max_steps);
  require_tolerance_params(in, setup);

  WorkPrecisionResult res;
  res.t_end = spec.t_end;
  res.h = spec.h;
  res.h_source = h_source;
  res.reference = work_precision_reference(in, spec, sys, hs.back(), progress);
  res.reference_description = res.reference.description;
  const Vec& ref = res.reference.values;
  if (progress) *progress << "reference: " << res.reference_description << "\n";

  // The points in the rows' order; run in rounds (see kRepeatBudget in the header).
  std::vector<Integrator*> instances;
  for (const auto& integ : setup.integrators) instances.push_back(integ.get());
  const TimedSweep c{in,
                     sys,
                     spec.model,
                     spec.params,
                     spec.integrators,
                     instances,
                     spec.t_end,
                     spec.atol_factor,
                     spec.max_runs(),
                     spec.seed,
                     tols,
                     hs,
                     ref,
                     progress};
  std::vector<WorkPrecisionPoint> points = work_precision_points(c);
  run_rounds(c, points);
  for (std::size_t idx = 0; idx < points.size(); ++idx) {
    res.rows.push_back(work_precision_row(c, points[idx], idx));
    WorkPrecisionRow& row = res.rows.back();
    row.at_reference_floor = row.stats.status == Status::ok && res.reference.error_estimate &&
                             *res.reference.error_estimate > 0 &&
                             row.error <= kFloorFactor * *res.reference.error_estimate;
  }
  return res;
}

// The CSV contract: the original contract columns first, then the solver counters and the
// timing spread (docs/formats.md, output files).
Table work_precision_table(const WorkPrecisionResult& res) {
  Table t{{"model", "integrator", "setting", "error", "f_evals", "jac_evals", "lin_solves", "steps",
           "wall_s", "status", "mescd"},
          {}};
  for (const auto& c : SolveStats::counter_names()) t.columns.push_back(c);
  const auto& timing = kWallTimingColumns;
  for (const char* c : {timing.median, timing.min, timing.ci_low, timing.ci_high, timing.runs,
                        "flag", "reference_error"})
    t.columns.push_back(c);
  const std::string ref_error =
      res.reference.error_estimate ? format_full(*res.reference.error_estimate) : "";
  for (const auto& r : res.rows) {
    const bool ok = r.stats.status == Status::ok;
    std::vector<std::string> row = {r.model,
                                    r.integrator,
                                    r.setting,
                                    ok ? format_full(r.error) : "",
                                    std::to_string(r.stats.f_evals),
                                    std::to_string(r.stats.jac_evals),
                                    SolveStats::count_text(r.stats.lin_solves),
                                    std::to_string(r.stats.steps),
                                    format_full(r.wall.median),
                                    to_string(r.stats.status),
                                    ok ? format_full(r.mescd) : ""};
    for (auto& v : r.stats.counter_values()) row.push_back(std::move(v));
    for (double w : {r.wall.median, r.wall.min, r.wall.ci_low, r.wall.ci_high})
      row.push_back(format_full(w));
    row.push_back(std::to_string(r.wall.repeats));
    row.push_back(r.at_reference_floor ? "reference_floor" : "");
    row.push_back(ref_error);
    t.rows.push_back(std::move(row));
  }
  return t;
}

namespace {

// The Markdown table: errors and times to a few digits, the wall time as "median [low, high]",
// and of the solver counters only those some row reports (non-zero).
Table work_precision_markdown_table(const WorkPrecisionResult& res) {
  const Table full = work_precision_table(res);
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(full.columns.begin(), full.columns.end(), name) -
                                    full.columns.begin());
  };
  std::vector<std::string> shown = {"integrator", "setting", "error",     "mescd",
                                    "steps",      "f_evals", "jac_evals", "lin_solves"};
  for (const auto& c : SolveStats::counter_names())
    for (const auto& row : full.rows)
      if (row[col(c)] != "0") {
        shown.push_back(c);
        break;
      }
  Table t{shown, {}};
  t.columns.insert(t.columns.end(),
                   {"wall s (median)", "95% interval", kWallTimingColumns.runs, "status"});
  for (const auto& row : full.rows) {
    std::vector<std::string> out;
    for (const auto& c : shown) {
      const std::string& v = row[col(c)];
      const bool counter = c != "integrator" && c != "setting" && c != "error" && c != "mescd";
      out.push_back(v.empty()      ? (counter ? SolveStats::count_shown(v) : "")
                    : c == "error" ? format_short(std::stod(v))
                    : c == "mescd" ? format_fixed(std::stod(v), 2)
                                   : v);
    }
    out.push_back(format_short(std::stod(row[col("wall_s_median")]), 2));
    out.push_back("[" + format_short(std::stod(row[col("wall_s_ci_low")]), 2) + ", " +
                  format_short(std::stod(row[col("wall_s_ci_high")]), 2) + "]");
    out.push_back(row[col(kWallTimingColumns.runs)]);
    out.push_back(row[col("flag")].empty() ? row[col("status")] : row[col("flag")]);
    t.rows.push_back(std::move(out));
  }
  return t;
}

}  // namespace

std::vector<std::string> tolerance_response_notes(const WorkPrecisionResult& res) {
  std::vector<std::string> names;
  for (const auto& r : res.rows)
    if (std::find(names.begin(), names.end(), r.integrator) == names.end())
      names.push_back(r.integrator);
  std::vector<std::string> notes;
  for (const auto& name : names) {
    std::vector<std::pair<double, double>> pts;  // (rtol, error)
    for (const auto& r : res.rows)
      if (r.integrator == name && r.stats.status == Status::ok &&
          r.setting.rfind("rtol=", 0) == 0 && std::isfinite(r.error) && r.error > 0)
        pts.emplace_back(std::stod(r.setting.substr(5)), r.error);
    if (pts.size() < 3) continue;
    std::sort(pts.begin(), pts.end());  // tightest first
    std::vector<double> log_tol, log_err;
    for (const auto& [t, e] : pts) {
      log_tol.push_back(std::log10(t));
      log_err.push_back(std::log10(e));
    }
    const std::optional<double> fit = least_squares_slope(log_tol, log_err);
    if (!fit) continue;  // every setting at one rtol
    const double slope = *fit;
    const auto& [tight, tight_error] = pts.front();
    if (slope >= kToleranceResponseMin || tight_error <= 100 * tight) continue;
    notes.push_back("**" + name + "**: the error does not follow the tolerance (slope " +
                    format_fixed(slope, 2) + " of log error against log rtol over rtol " +
                    format_short(pts.back().first) + " to " + format_short(tight) + "; error " +
                    format_short(tight_error) + " at rtol " + format_short(tight) +
                    "): its step control does not see its error on this problem (an embedded "
                    "estimate that vanishes or is filtered away), so these points are not a "
                    "work-precision curve although every run ended ok");
  }
  return notes;
}

namespace {

std::size_t rows_at_reference_floor(const WorkPrecisionResult& res) {
  return static_cast<std::size_t>(std::count_if(
      res.rows.begin(), res.rows.end(), [](const auto& r) { return r.at_reference_floor; }));
}

// What the errors are measured against, the reference's estimated error and its checks.
std::string reference_markdown(const WorkPrecisionResult& res) {
  const WorkPrecisionReference& ref = res.reference;
  std::ostringstream md;
  md << "Reference: " << ref.description << ". ";
  if (ref.kind == "exact") return md.str() + "\n";
  if (ref.error_estimate)
    md << "Its estimated error: " << format_short(*ref.error_estimate) << " (" << ref.error_source
       << "); a row within " << kFloorFactor
       << "× of it is marked `reference_floor` (its error measures the reference as much as the "
          "method; drawn hollow): "
       << rows_at_reference_floor(res) << " of " << res.rows.size() << " rows.";
  else
    md << "Its error is " << ref.error_source << ", so no row is checked against it.";
  md << "\n";
  if (!ref.numerical_description.empty())
    md << "\nNumerical reference" << (ref.kind == "numerical" ? "" : " (a check)") << ": "
       << ref.numerical_description << ".";
  if (ref.numerical_check)
    md << " Second run " << ref.check_description << ": difference "
       << format_short(*ref.numerical_check) << ".";
  else if (!ref.check_failure.empty())
    md << " Second run failed: " << ref.check_failure << ".";
  if (ref.has_published) {
    md << " Published-solution check: the numerical reference is "
       << (ref.published_distance ? format_short(*ref.published_distance) : "not known (no run)")
       << " from the published values at t = " << format_full(ref.published_t) << " ("
       << ref.published_source << "; stated accuracy " << format_short(ref.published_accuracy)
       << ").";
    if (ref.published_distance && ref.numerical_check &&
        *ref.published_distance >
            kFloorFactor * std::max(*ref.numerical_check, ref.published_accuracy))
      md << " That distance is more than " << kFloorFactor
         << "× the second run's difference: the second run underestimates the numerical "
            "reference's error.";
  }
  if (ref.method_studied && ref.kind == "numerical")
    md << " The numerical reference's method is also studied here: its own points near the "
          "reference's error share its errors.";
  md << "\n";
  return md.str();
}

// The JSON record of the reference and its checks (see "The reference" in the header).
nlohmann::json reference_json(const WorkPrecisionResult& res) {
  const WorkPrecisionReference& ref = res.reference;
  const auto opt = [](const std::optional<double>& x) {
    return x ? nlohmann::json(*x) : nlohmann::json();
  };
  const auto values = [](const Vec& y) {
    return std::vector<double>(y.data(), y.data() + y.size());
  };
  nlohmann::json j = {{"kind", ref.kind},
                      {"description", ref.description},
                      {"estimated_error", opt(ref.error_estimate)},
                      {"estimated_error_source", ref.error_source},
                      {"floor_factor", kFloorFactor},
                      {"rows_at_reference_floor", rows_at_reference_floor(res)}};
  if (!ref.numerical_description.empty()) {
    nlohmann::json n = {{"description", ref.numerical_description},
                        {"method_studied", ref.method_studied}};
    if (ref.numerical_failure.empty())
      n["values"] = values(ref.numerical_values);
    else
      n["failed"] = ref.numerical_failure;
    if (!ref.check_description.empty()) n["check_description"] = ref.check_description;
    n["check_difference"] = opt(ref.numerical_check);
    if (!ref.check_failure.empty()) n["check_failed"] = ref.check_failure;
    j["numerical"] = n;
  }
  if (ref.has_published)
    j["published"] = {
        {"t", ref.published_t},
        {"source", ref.published_source},
        {"values", values(ref.published_values)},
        {"stated_accuracy", ref.published_accuracy},
        {"stated_accuracy_rule", "max over i of 0.5*10^(floor(log10|y_i|) - 15) + 2^-53*|y_i| (" +
                                     std::to_string(kPublishedDigits) + " significant digits)"},
        {"distance_from_numerical", opt(ref.published_distance)}};
  return j;
}

std::string tolerance_response_markdown(const WorkPrecisionResult& res) {
  std::string md;
  for (const auto& n : tolerance_response_notes(res)) md += "- " + n + "\n";
  return md.empty() ? md : "\nTolerance response:\n\n" + md;
}
}  // namespace

void write_work_precision_outputs(const std::string& dir, const WorkPrecisionSpec& spec,
                                  const WorkPrecisionResult& res) {
  const std::filesystem::path d(dir);
  const Table t = work_precision_table(res);
  write_file_atomic(d / "work_precision.csv", t.to_csv());
  std::ostringstream md;
  md << "# Work-precision: " << spec.model
     << "\n\nError: max-norm at t_end = " << format_full(res.t_end) << " against "
     << res.reference_description << "; mescd with atol/rtol = " << format_full(spec.atol_factor)
     << ". Wall time: the median over up to " << spec.max_runs()
     << " runs per row (fewer for slow rows: a first run of " << format_short(kRepeatLongRun, 2)
     << " s or more runs once, and repeats stop once a row's runs total "
     << format_short(kRepeatBudget, 2) << " s), run in shuffled rounds (seed " << spec.seed
     << "), with a bootstrap 95% interval of the median (" << kBootstrapResamples
     << " resamples).\n\n"
     << reference_markdown(res) << "\n";
  std::vector<RunNote> notes;
  for (const auto& r : res.rows) notes.push_back({r.integrator + ", " + r.setting, &r.stats});
  md << work_precision_markdown_table(res).to_markdown() << tolerance_response_markdown(res)
     << failed_runs_markdown(notes)
     << "\nFull precision: `work_precision.csv`; metadata: `work_precision.json`.\n";
  write_file_atomic(d / "work_precision.md", md.str());
  nlohmann::json meta = run_metadata("work-precision", spec.to_json());
  add_step_study_metadata(meta, res.h, res.h_source, res.reference_description);
  meta["t_end_used"] = res.t_end;
  meta["reference_check"] = reference_json(res);
  meta["error_norm"] = "max-norm of the absolute error at t_end";
  meta["timing"] = {
      {"seed", spec.seed},
      {"max_repeats", spec.max_runs()},
      {"repeat_long_run_s", kRepeatLongRun},
      {"repeat_budget_s", kRepeatBudget},
      {"bootstrap_resamples", kBootstrapResamples},
      {"interval", "bootstrap 95% percentile interval of the median"},
      {"order", "rounds; each round every point still repeating, shuffled with the seed"},
      {"wall_s", "the median (wall_s_median)"}};
  write_file_atomic(d / "work_precision.json", meta.dump(2) + "\n");
}

namespace {

// The report's section: what was timed, the reference and each integrator's best point.
std::string work_precision_report(const WorkPrecisionSpec& spec, const WorkPrecisionResult& result,
                                  const std::string& note) {
  std::ostringstream md;
  md << note
     << " Fixed-step methods over h, references over rtol (atol = " << format_full(spec.atol_factor)
     << "·rtol). Wall time: the median over up to " << spec.max_runs()
     << " runs per setting in rounds shuffled with seed " << spec.seed
     << ", with a bootstrap 95% interval. Best error: the smallest not at the reference's "
        "floor.\n\n"
     << reference_markdown(result) << "\n";
  Table summary{{"integrator", "settings", "best error", "f_evals at best", "newton_iters at best",
                 "wall s at best (median [95% interval])", "status"},
                {}};
  for (const auto& name : spec.integrators) {
    int n = 0, floor = 0;
    const WorkPrecisionRow* best = nullptr;
    std::string status = "ok";
    for (const auto& r : result.rows) {
      if (r.integrator != name) continue;
      ++n;
      if (r.stats.status != Status::ok)
        status = to_string(r.stats.status);
      else if (r.at_reference_floor)
        ++floor;
      else if (!best || r.error < best->error)
        best = &r;
    }
    if (floor > 0) status += " (" + std::to_string(floor) + " at the reference floor)";
    summary.rows.push_back(
        {name, std::to_string(n), best ? format_short(best->error) : "-",
         best ? std::to_string(best->stats.f_evals) : "-",
         best ? SolveStats::count_shown(SolveStats::count_text(best->stats.newton_iters)) : "-",
         best ? format_short(best->wall.median, 2) + " [" + format_short(best->wall.ci_low, 2) +
                    ", " + format_short(best->wall.ci_high, 2) + "]"
              : "-",
         status});
  }
  md << summary.to_markdown() << tolerance_response_markdown(result) << "\n";
  return md.str();
}

const StudyFunctions<WorkPrecisionSpec, WorkPrecisionResult> kWorkPrecision{
    .run = [](const StudyInputs& in, const WorkPrecisionSpec& s,
              std::ostream* progress) { return run_work_precision(in, s, progress); },
    .unit_table = [](const WorkPrecisionSpec&,
                     const WorkPrecisionResult& r) { return work_precision_table(r); },
    .write =
        [](const std::filesystem::path& dir, const WorkPrecisionSpec& s,
           const WorkPrecisionResult& r, const std::string& title, const PlotOptions& plot,
           std::ostream& err) {
          write_work_precision_outputs(dir.string(), s, r);
          return plot_work_precision(dir / "work_precision.csv", title, plot, err);
        },
    .print_summary = [](const WorkPrecisionSpec&, const WorkPrecisionResult& r,
                        std::ostream& out) { out << work_precision_table(r).to_markdown(); },
    .report_markdown = work_precision_report,
    .default_title = [](const WorkPrecisionSpec& s) { return "Work-precision: " + s.model; },
    .helpers = [](const WorkPrecisionSpec& s) { return s.reference_integrators(); }};

using WorkPrecisionJob = TypedStudyJob<WorkPrecisionSpec, WorkPrecisionResult>;

}  // namespace

StudyKind work_precision_study_kind() {
  using P = ParamType;
  StudyKind k;
  k.name = "work-precision";
  k.stem = "work_precision";
  k.summary =
      "error against work: fixed-step methods over an h ladder, references over a tolerance "
      "ladder; writes work_precision.{csv,md,json}";
  k.options = step_study_options(work_precision_defaults());
  const std::vector<ParamSpec> own = {
      {"tol_levels", P::integer, "6", "number of tolerances (factor 10 apart)",
       Bounds::at_least(2)},
      {"rtol_max", P::real, "1e-05", "loosest relative tolerance (< 1)", Bounds::positive()},
      {"atol_factor", P::real, "0.001", "atol = atol_factor * rtol", Bounds::non_negative()},
      timing_repeats_option("5"),
      {"seed", P::integer, "1", "seed of the shuffled run order and of the bootstrap",
       Bounds::non_negative()}};
  k.options.insert(k.options.end(), own.begin(), own.end());
  k.unit_columns = work_precision_table(WorkPrecisionResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    WorkPrecisionSpec spec = with_inputs(WorkPrecisionSpec{}, t);
    spec.read_options(o);
    spec.validate();
    return std::make_unique<WorkPrecisionJob>(kWorkPrecision, t, std::move(spec));
  };
  return k;
}

const WorkPrecisionResult& work_precision_result(const StudyJob& job) {
  return typed_result<WorkPrecisionSpec, WorkPrecisionResult>(job);
}

WorkPrecisionResult run_work_precision(const WorkPrecisionSpec& spec, std::ostream* progress) {
  return run_work_precision(inputs_of(spec), spec, progress);
}

WorkPrecisionResult work_precision_study(const WorkPrecisionSpec& spec, const std::string& dir,
                                         std::ostream* progress, std::ostream& err,
                                         const PlotOptions& plot) {
  StudyContext ctx;
  ctx.force = force_output();
  ctx.plot = plot;
  ctx.progress = progress;
  ctx.err = &err;
  return work_precision_study(inputs_of(spec), spec, dir, ctx);
}

WorkPrecisionResult work_precision_study(const StudyInputs& in, WorkPrecisionSpec spec,
                                         const std::filesystem::path& dir,
                                         const StudyContext& ctx) {
  spec = with_inputs(std::move(spec), in);
  spec.validate();
  WorkPrecisionJob job(kWorkPrecision, in, std::move(spec));
  run_study_job(study_kind("work-precision"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench

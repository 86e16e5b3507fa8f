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

void WorkPrecisionSpec::validate() const {
  validate_step_study();
  choose_reference(*this, nullptr, 0, 0);  // the names: an unknown or a studied method
}

nlohmann::json WorkPrecisionSpec::to_json() const {
  nlohmann::json j = step_study_json();
  j["tol_levels"] = tol_levels;
  j["rtol_max"] = rtol_max;
  j["atol_factor"] = atol_factor;
  j["repeats"] = repeats;
  j["seed"] = seed;
  return j;
}

namespace {

// The first field in which a repeat differs from the first run ("" when none): the status, the
// final state (bit for bit) and every SolveStats field but the wall time.
std::string repeat_mismatch(const RunResult& a, const RunResult& b) {
  if (a.stats.status != b.stats.status)
    return "status (" + to_string(b.stats.status) + " against " + to_string(a.stats.status) + ")";
  if (a.y.size() != b.y.size() || a.y != b.y)
    return "the final state (max difference " +
           (a.y.size() == b.y.size() ? format_short(max_abs_diff(a.y, b.y)) : "size") + ")";
  const auto names = SolveStats::field_names();
  const auto va = a.stats.field_values(), vb = b.stats.field_values();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] != "wall_s" && va[i] != vb[i])
      return names[i] + " (" + vb[i] + " against " + va[i] + ")";
  if (a.stats.library_f_evals != b.stats.library_f_evals)
    return "library_f_evals (" + std::to_string(b.stats.library_f_evals) + " against " +
           std::to_string(a.stats.library_f_evals) + ")";
  return {};
}

double mescd(CVecRef y, CVecRef ref, double ratio) {
  double m = 0;
  for (Index i = 0; i < y.size(); ++i)
    m = std::max(m, std::abs(y[i] - ref[i]) / (ratio + std::abs(ref[i])));
  return -std::log10(m);
}

}  // namespace

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

WorkPrecisionReference work_precision_reference(const WorkPrecisionSpec& spec, const OdeSystem& sys,
                                                double h_fine, std::ostream* progress) {
  const ReferenceChoice choice = choose_reference(spec, &sys, spec.t_end, h_fine);
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

// One row's point: its integrator and ladder index, its first run and the wall times so far.
struct WorkPrecisionPoint {
  std::size_t integ, k;
  bool adaptive;
  RunResult first;
  std::vector<double> walls;
  bool stopped = false;
  std::string mismatch;
};

// What every point of one run shares: the resolved spec, the model, the ladders, the reference.
struct WorkPrecisionContext {
  const WorkPrecisionSpec& spec;
  const OdeSystem& sys;
  const Setup& setup;
  const std::vector<double>& tols;
  const std::vector<double>& hs;
  const Vec& ref;
  std::ostream* progress;
};

// An adaptive method runs over the tolerance ladder, so it must take rtol and atol (a user's
// integrator object without them would run at its own tolerance in every row).
void require_tolerance_params(const Setup& setup) {
  for (const auto& integ : setup.integrators) {
    if (!integ->supports_adaptive()) continue;
    const auto& entry = integrator_registry().at(integ->info().name);
    bool tolerances = false;
    for (const auto& p : entry.params) tolerances = tolerances || p.key == "rtol";
    require_input(tolerances, "integrator '" + integ->info().name +
                                  "' is adaptive but takes no rtol/atol parameters: "
                                  "work-precision cannot run it over a tolerance ladder "
                                  "(register it with rtol and atol, or give it a fixed-step mode)");
  }
}

// The points in the rows' order: per integrator, its tolerance ladder or its step ladder.
std::vector<WorkPrecisionPoint> work_precision_points(const WorkPrecisionContext& c) {
  std::vector<WorkPrecisionPoint> points;
  for (std::size_t i = 0; i < c.setup.integrators.size(); ++i) {
    const bool adaptive = c.setup.integrators[i]->supports_adaptive();
    for (std::size_t k = 0; k < (adaptive ? c.tols.size() : c.hs.size()); ++k)
      points.push_back(WorkPrecisionPoint{i, k, adaptive, {}, {}, false, {}});
  }
  return points;
}

// One run of a point: an adaptive method at its tolerance, a fixed-step method at its step.
RunResult run_point(const WorkPrecisionContext& c, const WorkPrecisionPoint& p) {
  const std::string& name = c.spec.integrators[p.integ];
  if (p.adaptive) {
    Params prm = c.spec.params;
    prm.set("rtol", format_full(c.tols[p.k]));
    prm.set("atol", format_full(c.tols[p.k] * c.spec.atol_factor));
    auto integ = integrator_registry().create(name, prm);
    return run_adaptive(c.sys, *integ, {c.spec.t_end, 0});
  }
  FixedStepOptions opt;
  opt.t_end = c.spec.t_end;
  opt.h = c.hs[p.k];
  return run_fixed_step(c.sys, *c.setup.integrators[p.integ], opt);
}

// Whether a point runs again in a later round (see kRepeatBudget in the header).
bool repeats_more(const WorkPrecisionContext& c, const WorkPrecisionPoint& p) {
  double total = 0;
  for (double w : p.walls) total += w;
  return !p.stopped && static_cast<int>(p.walls.size()) < c.spec.repeats &&
         p.walls.front() < kRepeatLongRun && total < kRepeatBudget;
}

// Records a point's first run and reports it as run `done` of `total`.
void record_first_run(const WorkPrecisionContext& c, WorkPrecisionPoint& p, RunResult r,
                      std::size_t done, std::size_t total) {
  p.walls.push_back(r.stats.wall_s);
  p.stopped = r.stats.status != Status::ok;  // a failed run is not repeated
  p.first = std::move(r);
  if (c.progress) {
    const RunResult& f = p.first;
    const bool ok = f.stats.status == Status::ok;
    *c.progress << "[" << done << "/" << total << "] " << c.spec.integrators[p.integ] << " "
                << (p.adaptive ? "rtol=" + format_short(c.tols[p.k], 0) : "h=" + format_full(f.h))
                << " error="
                << (ok ? format_short(max_abs_diff(f.y, c.ref)) : to_string(f.stats.status))
                << " f_evals=" << f.stats.f_evals << " (" << format_short(f.stats.wall_s, 2)
                << " s)\n"
                << std::flush;
  }
}

// Records a repeat: its wall time, or a stop on a timeout or on a result differing from run 1.
void record_repeat(WorkPrecisionPoint& p, const RunResult& r) {
  if (r.stats.status == Status::timeout) {
    p.stopped = true;  // over --max-wall: the runs so far stand
    return;
  }
  p.mismatch = repeat_mismatch(p.first, r);
  if (!p.mismatch.empty()) {
    p.mismatch = "not deterministic: run " + std::to_string(p.walls.size() + 1) +
                 " differs from run 1 in " + p.mismatch;
    p.stopped = true;
  } else {
    p.walls.push_back(r.stats.wall_s);
  }
}

// Runs the points in rounds, each shuffled with the seed, until no point repeats any more.
void run_rounds(const WorkPrecisionContext& c, std::vector<WorkPrecisionPoint>& points) {
  std::size_t done = 0;
  for (int round = 1; round <= c.spec.repeats; ++round) {
    std::size_t ran = 0;
    double spent = 0;
    for (const std::size_t idx : run_order(points.size(), c.spec.seed, round)) {
      WorkPrecisionPoint& p = points[idx];
      if (round > 1 && !repeats_more(c, p)) continue;
      RunResult r = run_point(c, p);
      ++ran;
      spent += r.stats.wall_s;
      if (round == 1)
        record_first_run(c, p, std::move(r), ++done, points.size());
      else
        record_repeat(p, r);
    }
    if (c.progress && round > 1 && ran > 0)
      *c.progress << "repeat round " << round << "/" << c.spec.repeats << ": " << ran << " runs ("
                  << format_short(spent, 2) << " s)\n"
                  << std::flush;
    if (ran == 0) break;
  }
}

// The row of point `idx`: its first run's counters, the timing spread, the errors.
WorkPrecisionRow work_precision_row(const WorkPrecisionContext& c, const WorkPrecisionPoint& p,
                                    std::size_t idx) {
  WorkPrecisionRow row;
  row.model = c.spec.model;
  row.integrator = c.spec.integrators[p.integ];
  row.setting = p.adaptive ? "rtol=" + format_short(c.tols[p.k], 0) : "h=" + format_full(p.first.h);
  row.stats = p.first.stats;
  row.wall = timing_spread(p.walls, c.spec.seed, idx);
  row.stats.wall_s = row.wall.median;
  if (!p.mismatch.empty()) {
    row.stats.status = Status::error;
    row.stats.message = p.mismatch;
  }
  const bool ok = row.stats.status == Status::ok;
  row.error = ok ? max_abs_diff(p.first.y, c.ref) : std::numeric_limits<double>::quiet_NaN();
  row.mescd =
      ok ? mescd(p.first.y, c.ref, c.spec.atol_factor) : std::numeric_limits<double>::quiet_NaN();
  return row;
}

}  // namespace

WorkPrecisionResult run_work_precision(const WorkPrecisionSpec& s, std::ostream* progress) {
  WorkPrecisionSpec spec = s;
  spec.validate();
  require_input(spec.tol_levels >= 2,
                "--tol-levels must be >= 2 (got " + std::to_string(spec.tol_levels) + ")");
  require_input(spec.repeats >= 1, "--repeats must be >= 1");
  require_input(spec.rtol_max > 0 && spec.rtol_max < 1, "--rtol-max must be in (0, 1)");
  require_input(spec.atol_factor >= 0, "--atol-factor must be >= 0");
  Setup setup = make_setup(spec.model, spec.integrators, spec.params);
  const OdeSystem& sys = *setup.model;
  const double t0 = sys.initial_time();
  spec.t_end = resolve_end_time(sys, spec.t_end == 0 ? std::nan("") : spec.t_end, spec.model).value;
  require_input(spec.t_end > t0, "--t-end must be > the model's initial time");
  choose_reference(spec, &sys, spec.t_end, 0);  // exact / published: the model has it
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
  require_tolerance_params(setup);

  WorkPrecisionResult res;
  res.t_end = spec.t_end;
  res.h = spec.h;
  res.h_source = h_source;
  res.reference = work_precision_reference(spec, sys, hs.back(), progress);
  res.reference_description = res.reference.description;
  const Vec& ref = res.reference.values;
  if (progress) *progress << "reference: " << res.reference_description << "\n";

  // The points in the rows' order; run in rounds (see kRepeatBudget in the header).
  const WorkPrecisionContext c{spec, sys, setup, tols, hs, ref, progress};
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

WorkPrecisionRow run_work_precision_setting(const OdeSystem& sys, const std::string& model,
                                            const std::string& integrator, const Params& params,
                                            bool adaptive, double setting, double atol_factor,
                                            double t_end, const Vec& ref, int repeats,
                                            unsigned long seed, std::size_t stream,
                                            double wall_limit_s) {
  WorkPrecisionSpec spec;
  spec.model = model;
  spec.params = params;
  spec.integrators = {integrator};
  spec.t_end = t_end;
  spec.atol_factor = atol_factor;
  spec.repeats = repeats;
  spec.seed = seed;
  Setup setup;
  setup.integrators.push_back(integrator_registry().create(integrator, params));
  const std::vector<double> tols = {setting}, hs = {setting};
  const WorkPrecisionContext c{spec, sys, setup, tols, hs, ref, nullptr};
  std::vector<WorkPrecisionPoint> points = {WorkPrecisionPoint{0, 0, adaptive, {}, {}, false, {}}};
  const double global = wall_limit();
  const double limit =
      global > 0 && (wall_limit_s <= 0 || global < wall_limit_s) ? global : wall_limit_s;
  const RowClock clock(limit);
  run_rounds(c, points);
  return work_precision_row(c, points.front(), stream);
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
  t.columns.insert(t.columns.end(), {"wall s (median)", "95% interval", "repeats", "status"});
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
    out.push_back(row[col("repeats")]);
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
     << ". Wall time: the median over up to " << spec.repeats
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
      {"max_repeats", spec.repeats},
      {"repeat_long_run_s", kRepeatLongRun},
      {"repeat_budget_s", kRepeatBudget},
      {"bootstrap_resamples", kBootstrapResamples},
      {"interval", "bootstrap 95% percentile interval of the median"},
      {"order", "rounds; each round every point still repeating, shuffled with the seed"},
      {"wall_s", "the median (wall_s_median)"}};
  write_file_atomic(d / "work_precision.json", meta.dump(2) + "\n");
}

namespace {

class WorkPrecisionJob : public StudyJob {
 public:
  explicit WorkPrecisionJob(WorkPrecisionSpec spec) : spec_(std::move(spec)) { spec_.validate(); }
  nlohmann::json spec_json() const override { return spec_.to_json(); }
  std::vector<std::string> helper_integrators() const override {
    return spec_.reference_integrators();
  }
  void run(std::ostream* progress) override { result_ = run_work_precision(spec_, progress); }
  Table unit_table() const override { return work_precision_table(result_); }
  bool write(const std::filesystem::path& dir, const std::string& title, const PlotOptions& plot,
             std::ostream& err) const override {
    write_work_precision_outputs(dir.string(), spec_, result_);
    return plot_work_precision(dir / "work_precision.csv", title, plot, err);
  }
  void print_summary(std::ostream& out) const override { out << unit_table().to_markdown(); }
  std::string report_markdown(const std::string& note) const override;
  std::string default_title() const override { return "Work-precision: " + spec_.model; }
  const WorkPrecisionResult& result() const { return result_; }

 private:
  WorkPrecisionSpec spec_;
  WorkPrecisionResult result_;
};

std::string WorkPrecisionJob::report_markdown(const std::string& note) const {
  std::ostringstream md;
  md << note << " Fixed-step methods over h, references over rtol (atol = "
     << format_full(spec_.atol_factor) << "·rtol). Wall time: the median over up to "
     << spec_.repeats << " runs per setting in rounds shuffled with seed " << spec_.seed
     << ", with a bootstrap 95% interval. Best error: the smallest not at the reference's "
        "floor.\n\n"
     << reference_markdown(result_) << "\n";
  Table summary{{"integrator", "settings", "best error", "f_evals at best", "newton_iters at best",
                 "wall s at best (median [95% interval])", "status"},
                {}};
  for (const auto& name : spec_.integrators) {
    int n = 0, floor = 0;
    const WorkPrecisionRow* best = nullptr;
    std::string status = "ok";
    for (const auto& r : result_.rows) {
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
  md << summary.to_markdown() << tolerance_response_markdown(result_) << "\n";
  return md.str();
}

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
    WorkPrecisionSpec spec;
    spec.model = t.model;
    spec.params = t.params;
    spec.integrators = t.integrators;
    read_step_study_options(o, spec);
    if (std::isnan(spec.h)) spec.h = 0;
    spec.tol_levels = static_cast<int>(o.integer("tol_levels"));
    spec.rtol_max = o.real("rtol_max");
    spec.atol_factor = o.real("atol_factor");
    spec.repeats = static_cast<int>(o.integer("repeats"));
    spec.seed = static_cast<unsigned long>(o.integer("seed"));
    return std::make_unique<WorkPrecisionJob>(std::move(spec));
  };
  return k;
}

const WorkPrecisionResult& work_precision_result(const StudyJob& job) {
  return dynamic_cast<const WorkPrecisionJob&>(job).result();
}

WorkPrecisionResult work_precision_study(const WorkPrecisionSpec& spec, const std::string& dir,
                                         std::ostream* progress, std::ostream& err,
                                         const PlotOptions& plot) {
  StudyContext ctx;
  ctx.force = force_output();
  ctx.plot = plot;
  ctx.progress = progress;
  ctx.err = &err;
  return work_precision_study(spec, StudyObjects{}, dir, ctx);
}

WorkPrecisionResult work_precision_study(WorkPrecisionSpec spec, const StudyObjects& objects,
                                         const std::filesystem::path& dir,
                                         const StudyContext& ctx) {
  const ScopedStudyObjects scope(objects, spec.model, spec.integrators);
  WorkPrecisionJob job(std::move(spec));
  run_study_job(study_kind("work-precision"), job, dir, ctx);
  return job.result();
}

WorkPrecisionResult run_work_precision(WorkPrecisionSpec spec, const StudyObjects& objects,
                                       std::ostream* progress) {
  const ScopedStudyObjects scope(objects, spec.model, spec.integrators);
  return run_work_precision(static_cast<const WorkPrecisionSpec&>(spec), progress);
}

WorkPrecisionResult run_work_precision(WorkPrecisionSpec spec, const SystemFactory& system,
                                       std::ostream* progress) {
  return run_work_precision(std::move(spec), StudyObjects{system, {}}, progress);
}

}  // namespace stiffbench

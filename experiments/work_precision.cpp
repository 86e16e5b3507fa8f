#include "experiments/work_precision.hpp"

#include <cmath>
#include <filesystem>
#include <limits>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "experiments/catalog.hpp"

namespace stiffbench {

namespace {

// The declared defaults of the step ladder and the reference (cvode_bdf at rtol 1e-14: on
// HIRES it agrees with the IVP test set's published solution to ~1e-13, rtol 1e-12 is off by
// ~1e-11).
StepStudyDefaults work_precision_defaults() {
  StepStudyDefaults d;
  d.t_end_help = "final time (default: the model's literature end time)";
  d.h_help =
      "coarsest step of fixed-step methods (default: the model's suggested step, else "
      "(t_end - t0)/16000)";
  d.ladder_levels = "4";
  d.ref_rtol = "1e-14";
  d.ref_atol = "1e-16";
  d.ref_help = "exact | METHOD; default: exact where available, else cvode_bdf";
  return d;
}

}  // namespace

WorkPrecisionSpec::WorkPrecisionSpec() {
  t_end = 0;
  h = 0;
  apply_defaults(work_precision_defaults());
}

nlohmann::json WorkPrecisionSpec::to_json() const {
  nlohmann::json j = step_study_json();
  j["tol_levels"] = tol_levels;
  j["rtol_max"] = rtol_max;
  j["atol_factor"] = atol_factor;
  j["repeats"] = repeats;
  return j;
}

namespace {

double mescd(CVecRef y, CVecRef ref, double ratio) {
  double m = 0;
  for (Index i = 0; i < y.size(); ++i)
    m = std::max(m, std::abs(y[i] - ref[i]) / (ratio + std::abs(ref[i])));
  return -std::log10(m);
}

}  // namespace

WorkPrecisionResult run_work_precision(const WorkPrecisionSpec& s, std::ostream* progress) {
  WorkPrecisionSpec spec = s;
  spec.validate_step_study();
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

  // An adaptive method runs over the tolerance ladder, so it must take rtol and atol (a user's
  // integrator object without them would run at its own tolerance in every row).
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
  WorkPrecisionResult res;
  res.t_end = spec.t_end;
  res.h = spec.h;
  res.h_source = h_source;
  const Vec ref = reference_at_end(spec, sys, spec.t_end, hs.back(), &res.reference_description);
  if (progress) *progress << "reference: " << res.reference_description << "\n";

  std::size_t total = 0, done = 0;
  for (const auto& integ : setup.integrators)
    total += integ->supports_adaptive() ? tols.size() : hs.size();
  for (std::size_t i = 0; i < setup.integrators.size(); ++i) {
    const std::string name = spec.integrators[i];
    const bool adaptive = setup.integrators[i]->supports_adaptive();
    const std::size_t n_settings = adaptive ? tols.size() : hs.size();
    for (std::size_t k = 0; k < n_settings; ++k) {
      WorkPrecisionRow row;
      row.model = spec.model;
      row.integrator = name;
      double best_wall = std::numeric_limits<double>::infinity();
      RunResult r;
      for (int rep = 0; rep < spec.repeats; ++rep) {
        if (adaptive) {
          Params p = spec.params;
          p.set("rtol", format_full(tols[k]));
          p.set("atol", format_full(tols[k] * spec.atol_factor));
          auto integ = integrator_registry().create(name, p);
          r = run_adaptive(sys, *integ, {spec.t_end, 0});
          row.setting = "rtol=" + format_short(tols[k], 0);
        } else {
          FixedStepOptions opt;
          opt.t_end = spec.t_end;
          opt.h = hs[k];
          r = run_fixed_step(sys, *setup.integrators[i], opt);
          row.setting = "h=" + format_full(r.h);
        }
        best_wall = std::min(best_wall, r.stats.wall_s);
        if (r.stats.status != Status::ok) break;  // a failed run is not repeated
      }
      row.stats = r.stats;
      row.stats.wall_s = best_wall;
      const bool ok = r.stats.status == Status::ok;
      row.error = ok ? max_abs_diff(r.y, ref) : std::numeric_limits<double>::quiet_NaN();
      row.mescd = ok ? mescd(r.y, ref, spec.atol_factor) : std::numeric_limits<double>::quiet_NaN();
      res.rows.push_back(row);
      if (progress) {
        *progress << "[" << ++done << "/" << total << "] " << name << " " << row.setting
                  << " error=" << (ok ? format_short(row.error) : to_string(r.stats.status))
                  << " f_evals=" << row.stats.f_evals << " (" << format_short(best_wall, 2)
                  << " s)\n"
                  << std::flush;
      }
    }
  }
  return res;
}

Table work_precision_table(const WorkPrecisionResult& res) {
  Table t{{"model", "integrator", "setting", "error", "f_evals", "jac_evals", "lin_solves", "steps",
           "wall_s", "status", "mescd"},
          {}};
  for (const auto& r : res.rows) {
    const bool ok = r.stats.status == Status::ok;
    t.rows.push_back({r.model, r.integrator, r.setting, ok ? format_full(r.error) : "",
                      std::to_string(r.stats.f_evals), std::to_string(r.stats.jac_evals),
                      std::to_string(r.stats.lin_solves), std::to_string(r.stats.steps),
                      format_full(r.stats.wall_s), to_string(r.stats.status),
                      ok ? format_full(r.mescd) : ""});
  }
  return t;
}

void write_work_precision_outputs(const std::string& dir, const WorkPrecisionSpec& spec,
                                  const WorkPrecisionResult& res) {
  const std::filesystem::path d(dir);
  const Table t = work_precision_table(res);
  write_file_atomic(d / "work_precision.csv", t.to_csv());
  std::ostringstream md;
  md << "# Work-precision: " << spec.model
     << "\n\nError: max-norm at t_end = " << format_full(res.t_end) << " against "
     << res.reference_description << "; mescd with atol/rtol = " << format_full(spec.atol_factor)
     << "; wall time: minimum over " << spec.repeats << " runs.\n\n";
  Table short_t = t;
  for (auto& row : short_t.rows) {
    if (!row[3].empty()) row[3] = format_short(std::stod(row[3]));
    row[8] = format_short(std::stod(row[8]), 2);
    if (!row[10].empty()) row[10] = format_fixed(std::stod(row[10]), 2);
  }
  std::vector<RunNote> notes;
  for (const auto& r : res.rows) notes.push_back({r.integrator + ", " + r.setting, &r.stats});
  md << short_t.to_markdown() << failed_runs_markdown(notes)
     << "\nFull precision: `work_precision.csv`; metadata: `work_precision.json`.\n";
  write_file_atomic(d / "work_precision.md", md.str());
  nlohmann::json meta = run_metadata("work-precision", spec.to_json());
  add_step_study_metadata(meta, res.h, res.h_source, res.reference_description);
  meta["t_end_used"] = res.t_end;
  meta["error_norm"] = "max-norm of the absolute error at t_end";
  write_file_atomic(d / "work_precision.json", meta.dump(2) + "\n");
}

namespace {

class WorkPrecisionJob : public StudyJob {
 public:
  explicit WorkPrecisionJob(WorkPrecisionSpec spec) : spec_(std::move(spec)) {
    spec_.validate_step_study();
  }
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
  md << note << " Reference: " << result_.reference_description
     << ". Fixed-step methods over h, references over rtol (atol = "
     << format_full(spec_.atol_factor) << "·rtol).\n\n";
  Table summary{{"integrator", "settings", "best error", "f_evals at best", "status"}, {}};
  for (const auto& name : spec_.integrators) {
    int n = 0;
    double best = std::numeric_limits<double>::infinity();
    long fe = 0;
    std::string status = "ok";
    for (const auto& r : result_.rows) {
      if (r.integrator != name) continue;
      ++n;
      if (r.stats.status != Status::ok)
        status = to_string(r.stats.status);
      else if (r.error < best) {
        best = r.error;
        fe = r.stats.f_evals;
      }
    }
    summary.rows.push_back({name, std::to_string(n), std::isfinite(best) ? format_short(best) : "-",
                            std::to_string(fe), status});
  }
  md << summary.to_markdown() << "\n";
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
      {"repeats", P::integer, "3", "runs per setting; wall time is the minimum",
       Bounds::at_least(1)}};
  k.options.insert(k.options.end(), own.begin(), own.end());
  k.unit_columns = work_precision_table(WorkPrecisionResult{}).columns;
  k.make = [](const StudyTarget& t, const Params& o, const StudyContext&) {
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

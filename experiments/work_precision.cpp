#include "experiments/work_precision.hpp"

#include <cmath>
#include <filesystem>
#include <limits>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "experiments/catalog.hpp"

namespace stiffbench {

nlohmann::json WorkPrecisionSpec::to_json() const {
  return {{"model", model},
          {"params", params.values()},
          {"integrators", integrators},
          {"t_end", t_end},
          {"h", h},
          {"levels", levels},
          {"refine", refine},
          {"tol_levels", tol_levels},
          {"rtol_max", rtol_max},
          {"atol_factor", atol_factor},
          {"repeats", repeats},
          {"reference", reference},
          {"reference_rtol", reference_rtol},
          {"reference_atol", reference_atol}};
}

namespace {

// The reference state at t_end, with a description for the metadata.
Vec reference_state(const WorkPrecisionSpec& spec, const OdeSystem& sys, double t_end,
                    double h_fine, std::string* description) {
  Vec y(sys.dimension());
  const bool exact = spec.reference == "exact" || (spec.reference == "auto" && sys.has_exact());
  if (exact) {
    require_input(sys.has_exact(),
                  "--reference exact: model '" + sys.name() + "' has no exact solution");
    sys.exact(t_end, y);
    *description = "exact";
    return y;
  }
  const std::string method = spec.reference == "auto" ? "cvode_bdf" : spec.reference;
  Params p = spec.params;
  const auto& entry = integrator_registry().at(method);
  bool has_rtol = false;
  for (const auto& ps : entry.params) has_rtol = has_rtol || ps.key == "rtol";
  if (has_rtol) {
    p.set("rtol", format_full(spec.reference_rtol));
    p.set("atol", format_full(spec.reference_atol));
  }
  auto integ = integrator_registry().create(method, p);
  RunResult r;
  if (integ->supports_adaptive()) {
    r = run_adaptive(sys, *integ, {t_end, 0});
    *description =
        method + " adaptive, rtol = " + p.values().at("rtol") + ", atol = " + p.values().at("atol");
  } else {
    FixedStepOptions opt;
    opt.t_end = t_end;
    opt.h = h_fine / 16;
    r = run_fixed_step(sys, *integ, opt);
    *description = method + " with h = (finest h)/16 = " + format_full(opt.h);
  }
  if (r.stats.status != Status::ok)
    throw std::runtime_error("reference run of '" + method + "' failed: " + r.stats.message);
  return r.y;
}

double mescd(CVecRef y, CVecRef ref, double ratio) {
  double m = 0;
  for (Index i = 0; i < y.size(); ++i)
    m = std::max(m, std::abs(y[i] - ref[i]) / (ratio + std::abs(ref[i])));
  return -std::log10(m);
}

}  // namespace

WorkPrecisionResult run_work_precision(const WorkPrecisionSpec& s, std::ostream* progress) {
  WorkPrecisionSpec spec = s;
  require_input(!spec.integrators.empty(), "--integrators: no integrator given");
  require_input(spec.levels >= 2,
                "--levels must be >= 2 (got " + std::to_string(spec.levels) + ")");
  require_input(spec.tol_levels >= 2,
                "--tol-levels must be >= 2 (got " + std::to_string(spec.tol_levels) + ")");
  require_input(spec.refine > 1, "--refine must be > 1");
  require_input(spec.repeats >= 1, "--repeats must be >= 1");
  require_input(spec.rtol_max > 0 && spec.rtol_max < 1, "--rtol-max must be in (0, 1)");
  require_input(spec.atol_factor >= 0, "--atol-factor must be >= 0");
  Setup setup = make_setup(spec.model, spec.integrators, spec.params);
  const OdeSystem& sys = *setup.model;
  const double t0 = sys.initial_time();
  if (spec.t_end == 0) {
    const auto literature = sys.end_time();
    require_input(literature.has_value(),
                  "--t-end is required: model '" + spec.model + "' has no default end time");
    spec.t_end = *literature;
  }
  require_input(spec.t_end > t0, "--t-end must be > the model's initial time");
  std::string h_source = "--h";
  if (spec.h == 0) {
    // The model's suggested step (its CFL limit) where it has one, else a fine default.
    if (const auto suggested = sys.suggested_step()) {
      spec.h = suggested->h;
      h_source = "suggested step: " + suggested->rule;
    } else {
      spec.h = (spec.t_end - t0) / 16000;
      h_source = "(t_end - t0)/16000";
    }
    if (progress) *progress << "coarsest h = " << format_full(spec.h) << " (" << h_source << ")\n";
  }
  require_input(spec.h > 0, "--h must be > 0");
  std::vector<double> hs, tols;
  for (int k = 0; k < spec.levels; ++k) hs.push_back(spec.h / std::pow(spec.refine, k));
  for (int k = 0; k < spec.tol_levels; ++k) tols.push_back(spec.rtol_max / std::pow(10.0, k));
  for (double h : hs) fixed_step_count(t0, spec.t_end, h, FixedStepOptions{}.max_steps);

  WorkPrecisionResult res;
  res.t_end = spec.t_end;
  res.h = spec.h;
  res.h_source = h_source;
  const Vec ref = reference_state(spec, sys, spec.t_end, hs.back(), &res.reference_description);
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
  meta["reference"] = res.reference_description;
  meta["t_end_used"] = res.t_end;
  meta["h_used"] = res.h;
  meta["h_source"] = res.h_source;
  meta["error_norm"] = "max-norm of the absolute error at t_end";
  write_file_atomic(d / "work_precision.json", meta.dump(2) + "\n");
}

WorkPrecisionResult work_precision_study(const WorkPrecisionSpec& spec, const std::string& dir,
                                         std::ostream* progress, std::ostream& err,
                                         const PlotOptions& plot) {
  require_output_dir(dir);
  check_study_output(dir, "work_precision", spec.to_json(), force_output(), &err);
  WorkPrecisionResult res = run_work_precision(spec, progress);
  write_work_precision_outputs(dir, spec, res);
  plot_work_precision(std::filesystem::path(dir) / "work_precision.csv",
                      "Work-precision: " + spec.model, plot, err);
  return res;
}

WorkPrecisionResult run_work_precision(WorkPrecisionSpec spec, const SystemFactory& system,
                                       std::ostream* progress) {
  spec.model = register_system(system, spec.model);
  return run_work_precision(static_cast<const WorkPrecisionSpec&>(spec), progress);
}

}  // namespace stiffbench

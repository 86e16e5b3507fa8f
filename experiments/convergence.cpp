#include "experiments/convergence.hpp"

#include <cmath>
#include <filesystem>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "experiments/catalog.hpp"

namespace stiffbench {

void ConvergenceSpec::validate() const {
  require_input(std::isfinite(t_end) && t_end > 0,
                "--t-end must be > 0 (got " + format_full(t_end) + ")");
  require_input(std::isnan(h) || (std::isfinite(h) && h > 0),
                "--h must be > 0 (got " + format_full(h) + ")");
  require_input(levels >= 2, "--levels must be >= 2 (got " + std::to_string(levels) + ")");
  require_input(std::isfinite(refine) && refine > 1,
                "--refine must be > 1 (got " + format_full(refine) + ")");
  require_input(!integrators.empty(), "--integrators: no integrator given");
}

nlohmann::json ConvergenceSpec::to_json() const {
  return {{"model", model},
          {"params", params.values()},
          {"integrators", integrators},
          {"t_end", t_end},
          {"h", h},
          {"levels", levels},
          {"refine", refine},
          {"reference", reference}};
}

namespace {

// The reference solution at requested times: exact, or a fine run of a reference method.
class Reference {
 public:
  Reference(const ConvergenceSpec& spec, const OdeSystem& sys, double h_fine) : sys_(sys) {
    const bool want_exact =
        spec.reference == "exact" || (spec.reference == "auto" && sys.has_exact());
    if (spec.reference == "auto" && !sys.has_exact()) {
      throw BadInput("model '" + sys.name() +
                     "' has no exact solution: pass --reference METHOD (e.g. --reference rk4)");
    }
    if (want_exact) {
      require_input(sys.has_exact(),
                    "--reference exact: model '" + sys.name() + "' has no exact solution");
      description_ = "exact";
      return;
    }
    method_ = spec.reference;
    integrator_ = integrator_registry().create(method_, spec.params);
    check_compatible(integrator_->info(), sys);
    h_ = h_fine / 16.0;
    description_ = method_ + " with h = (finest h)/16 = " + format_full(h_);
  }

  // y_ref(t) starting from the model's initial state.
  Vec at(double t) const {
    Vec y(sys_.dimension());
    if (!integrator_) {
      sys_.exact(t, y);
      return y;
    }
    FixedStepOptions opt;
    opt.t_end = t;
    opt.h = h_;
    const RunResult r = run_fixed_step(sys_, *integrator_, opt);
    if (r.stats.status != Status::ok) {
      throw std::runtime_error("reference run of '" + method_ + "' failed: " + r.stats.message);
    }
    return r.y;
  }

  const std::string& description() const { return description_; }

 private:
  const OdeSystem& sys_;
  std::unique_ptr<Integrator> integrator_;
  std::string method_, description_;
  double h_ = 0;
};

void add_observed_orders(std::vector<ConvergenceRow>& rows) {
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& a = rows[i - 1];
    auto& b = rows[i];
    if (a.integrator != b.integrator) continue;
    if (a.stats.status != Status::ok || b.stats.status != Status::ok) continue;
    if (!(a.error > 0) || !(b.error > 0)) continue;
    b.observed_order = std::log(a.error / b.error) / std::log(a.h / b.h);
  }
}

std::string progress_line(std::size_t k, std::size_t n, const ConvergenceRow& r) {
  std::ostringstream os;
  os << "[" << k << "/" << n << "] " << r.model << " " << r.integrator << " h=" << format_short(r.h)
     << " error="
     << (r.stats.status == Status::ok ? format_short(r.error) : to_string(r.stats.status)) << " ("
     << format_short(r.stats.wall_s, 2) << " s)\n";
  return os.str();
}

ConvergenceResult run_study(const ConvergenceSpec& given, std::ostream* progress, bool local) {
  given.validate();
  Setup setup = make_setup(given.model, given.integrators, given.params);
  const OdeSystem& sys = *setup.model;
  ConvergenceSpec spec = given;
  std::string h_source = "--h";
  if (std::isnan(spec.h)) {
    const auto suggested = sys.suggested_step();
    require_input(suggested.has_value(),
                  "--h is required: model '" + spec.model + "' offers no suggested step");
    spec.h = suggested->h;
    h_source = "suggested step: " + suggested->rule;
    if (progress)
      *progress << "no --h given: starting from the model's suggested step h = "
                << format_full(spec.h) << " (" << suggested->rule << ")\n";
  }
  const double t0 = sys.initial_time();
  require_input(spec.t_end > t0, "--t-end must be > the model's initial time");
  for (const auto& integ : setup.integrators)
    require_input(
        integ->supports_fixed_step(),
        "integrator '" + integ->info().name +
            "' is adaptive only: a step-size study needs fixed steps (use work-precision)");

  // Actual step sizes are fixed by the driver's N = round(T/h) rule (global study); the local
  // study uses h_k exactly.
  std::vector<double> hs;
  for (int k = 0; k < spec.levels; ++k) hs.push_back(spec.h / std::pow(spec.refine, k));
  for (double h : hs) fixed_step_count(t0, spec.t_end, h, FixedStepOptions{}.max_steps);

  Reference ref(spec, sys, hs.back());
  ConvergenceResult result;
  result.reference_description = ref.description();
  result.h = spec.h;
  result.h_source = h_source;

  std::vector<Vec> ref_values;  // per level for local, one value for global
  if (local) {
    for (double h : hs) ref_values.push_back(ref.at(t0 + h));
  } else {
    ref_values.push_back(ref.at(spec.t_end));
  }

  const std::size_t total = setup.integrators.size() * hs.size();
  std::size_t done = 0;
  const Vec y0 = sys.initial_state();
  for (auto& integ : setup.integrators) {
    for (std::size_t k = 0; k < hs.size(); ++k) {
      ConvergenceRow row;
      row.model = spec.model;
      row.integrator = integ->info().name;
      row.order = integ->info().order;
      FixedStepOptions opt;
      opt.t_end = local ? t0 + hs[k] : spec.t_end;
      opt.h = hs[k];
      const RunResult r = run_fixed_step_from(sys, *integ, t0, y0, opt);
      row.h = r.h;
      row.steps = r.n_steps;
      row.stats = r.stats;
      row.error = r.stats.status == Status::ok ? max_abs_diff(r.y, ref_values[local ? k : 0])
                                               : std::numeric_limits<double>::quiet_NaN();
      result.rows.push_back(row);
      if (progress) *progress << progress_line(++done, total, row) << std::flush;
    }
  }
  add_observed_orders(result.rows);
  return result;
}

std::string optional_full(const std::optional<double>& x) { return x ? format_full(*x) : ""; }

}  // namespace

ConvergenceResult run_convergence(const ConvergenceSpec& spec, std::ostream* progress) {
  return run_study(spec, progress, false);
}

ConvergenceResult run_local_error(const ConvergenceSpec& spec, std::ostream* progress) {
  return run_study(spec, progress, true);
}

std::optional<double> fitted_order(const std::vector<ConvergenceRow>& rows,
                                   const std::string& integrator, int points) {
  std::vector<std::pair<double, double>> xy;
  for (const auto& r : rows)
    if (r.integrator == integrator && r.stats.status == Status::ok && r.error > 0)
      xy.emplace_back(std::log(r.h), std::log(r.error));
  if (xy.size() < 2) return std::nullopt;
  const std::size_t n = std::min(xy.size(), static_cast<std::size_t>(points));
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = xy.size() - n; i < xy.size(); ++i) {
    sx += xy[i].first;
    sy += xy[i].second;
    sxx += xy[i].first * xy[i].first;
    sxy += xy[i].first * xy[i].second;
  }
  const double dn = static_cast<double>(n);
  return (dn * sxy - sx * sy) / (dn * sxx - sx * sx);
}

std::optional<double> last_observed_order(const std::vector<ConvergenceRow>& rows,
                                          const std::string& integrator) {
  std::optional<double> last;
  for (const auto& r : rows)
    if (r.integrator == integrator) last = r.observed_order;
  return last;
}

Table convergence_table(const ConvergenceResult& res) {
  Table t{{"model", "integrator", "order", "h", "steps", "error", "observed_order", "f_evals",
           "jac_evals", "lin_solves", "wall_s", "status"},
          {}};
  for (const auto& r : res.rows) {
    t.rows.push_back({r.model, r.integrator, std::to_string(r.order), format_full(r.h),
                      std::to_string(r.steps),
                      r.stats.status == Status::ok ? format_full(r.error) : "",
                      optional_full(r.observed_order), std::to_string(r.stats.f_evals),
                      std::to_string(r.stats.jac_evals), std::to_string(r.stats.lin_solves),
                      format_full(r.stats.wall_s), to_string(r.stats.status)});
  }
  return t;
}

Table local_error_table(const ConvergenceResult& res) {
  Table t{{"model", "integrator", "order", "h", "local_error", "observed_order"}, {}};
  for (const auto& r : res.rows) {
    t.rows.push_back({r.model, r.integrator, std::to_string(r.order), format_full(r.h),
                      r.stats.status == Status::ok ? format_full(r.error) : "",
                      optional_full(r.observed_order)});
  }
  return t;
}

namespace {

std::string markdown_report(const std::string& name, const ConvergenceSpec& spec,
                            const ConvergenceResult& res, bool local) {
  std::ostringstream os;
  os << "# " << (local ? "Local error" : "Convergence") << ": " << spec.model << "\n\n";
  os << "Error: max-norm "
     << (local ? "after one step of size h from the initial state"
               : "at t_end = " + format_full(spec.t_end))
     << "; reference: " << res.reference_description << ".";
  if (!spec.params.empty()) {
    os << " Parameters:";
    for (const auto& [k, v] : spec.params.values()) os << " " << k << "=" << v;
    os << ".";
  }
  os << "\n\n";
  // Summary: expected vs observed order per integrator.
  Table summary{{"integrator", local ? "expected slope (order+1)" : "order", "last observed",
                 "least-squares (last 3)", "within 0.2"},
                {}};
  std::vector<std::string> seen;
  for (const auto& r : res.rows) {
    if (!seen.empty() && seen.back() == r.integrator) continue;
    seen.push_back(r.integrator);
    const int expected = r.order + (local ? 1 : 0);
    const auto last = last_observed_order(res.rows, r.integrator);
    const auto fit = fitted_order(res.rows, r.integrator);
    summary.rows.push_back({r.integrator, std::to_string(expected),
                            last ? format_fixed(*last) : "-", fit ? format_fixed(*fit) : "-",
                            last ? (std::abs(*last - expected) <= 0.2 ? "yes" : "no") : "-"});
  }
  os << summary.to_markdown() << "\n";
  Table detail = local ? local_error_table(res) : convergence_table(res);
  // Shorter numbers in the Markdown copy; the CSV keeps full precision.
  for (auto& row : detail.rows)
    for (std::size_t c = 0; c < detail.columns.size(); ++c) {
      const auto& col = detail.columns[c];
      if ((col == "h" || col == "error" || col == "local_error" || col == "wall_s") &&
          !row[c].empty())
        row[c] = format_short(std::stod(row[c]), col == "wall_s" ? 2 : 3);
      if (col == "observed_order" && !row[c].empty()) row[c] = format_fixed(std::stod(row[c]));
    }
  os << detail.to_markdown();
  os << "\nFull-precision values: `" << name << ".csv`; metadata: `" << name << ".json`.\n";
  return os.str();
}

}  // namespace

void write_convergence_outputs(const std::string& dir, const std::string& name,
                               const ConvergenceSpec& spec, const ConvergenceResult& res,
                               bool local) {
  const std::filesystem::path d(dir);
  const Table t = local ? local_error_table(res) : convergence_table(res);
  write_file_atomic(d / (name + ".csv"), t.to_csv());
  write_file_atomic(d / (name + ".md"), markdown_report(name, spec, res, local));
  nlohmann::json spec_json = spec.to_json();
  spec_json["h"] = res.h;
  spec_json["h_source"] = res.h_source;
  nlohmann::json meta = run_metadata(local ? "local-error" : "convergence", spec_json);
  meta["reference"] = res.reference_description;
  meta["error_norm"] = "max-norm of the absolute error";
  write_file_atomic(d / (name + ".json"), meta.dump(2) + "\n");
}

}  // namespace stiffbench

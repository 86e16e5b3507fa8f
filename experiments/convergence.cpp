#include "experiments/convergence.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/catalog.hpp"

namespace stiffbench {

std::vector<double> StepStudySpec::step_ladder(double h0) const {
  std::vector<double> hs;
  for (int k = 0; k < levels; ++k) hs.push_back(h0 / std::pow(refine, k));
  return hs;
}

void StepStudySpec::validate_step_study() const {
  require_input(std::isnan(h) || (std::isfinite(h) && h >= 0),
                "--h must be > 0 (got " + format_full(h) + ")");
  require_input(levels >= 2, "--levels must be >= 2 (got " + std::to_string(levels) + ")");
  require_input(std::isfinite(refine) && refine > 1,
                "--refine must be > 1 (got " + format_full(refine) + ")");
  require_input(!integrators.empty(), "--integrators: no integrator given");
  if (reference_rtol)
    require_input(std::isfinite(*reference_rtol) && *reference_rtol > 0,
                  "--reference-rtol must be > 0 (got " + format_full(*reference_rtol) + ")");
  if (reference_atol)
    require_input(std::isfinite(*reference_atol) && *reference_atol > 0,
                  "--reference-atol must be > 0 (got " + format_full(*reference_atol) + ")");
}

nlohmann::json StepStudySpec::step_study_json() const {
  return {{"model", model},
          {"params", params.values()},
          {"integrators", integrators},
          {"t_end", t_end},
          {"h", h},
          {"levels", levels},
          {"refine", refine},
          {"reference", reference},
          {"reference_rtol", reference_rtol ? nlohmann::json(*reference_rtol) : nlohmann::json()},
          {"reference_atol", reference_atol ? nlohmann::json(*reference_atol) : nlohmann::json()}};
}

std::vector<std::string> StepStudySpec::reference_integrators() const { return {reference}; }

void StepStudySpec::apply_defaults(const StepStudyDefaults& d) {
  levels = std::stoi(d.ladder_levels);
  if (!d.ref_rtol.empty()) reference_rtol = std::stod(d.ref_rtol);
  if (!d.ref_atol.empty()) reference_atol = std::stod(d.ref_atol);
}

void add_step_study_metadata(nlohmann::json& meta, double h_used, const std::string& h_source,
                             const std::string& reference) {
  meta["h_used"] = h_used;
  meta["h_source"] = h_source;
  meta["reference"] = reference;
}

std::vector<ParamSpec> step_study_options(const StepStudyDefaults& d) {
  using P = ParamType;
  return {
      {"t_end", P::real, "", d.t_end_help, Bounds::positive()},
      {"h", P::real, "", d.h_help, Bounds::positive()},
      {"levels", P::integer, d.ladder_levels, "number of step sizes", Bounds::at_least(2)},
      {"refine", P::real, "2", "ratio between consecutive step sizes", Bounds::above(1)},
      {"reference", P::text, "auto", d.ref_help},
      {"reference_rtol", P::real, d.ref_rtol, "relative tolerance of an adaptive reference run",
       Bounds::positive()},
      {"reference_atol", P::real, d.ref_atol, "absolute tolerance of an adaptive reference run",
       Bounds::positive()},
  };
}

void read_step_study_options(const Params& o, StepStudySpec& spec) {
  if (o.contains("t_end")) spec.t_end = o.real("t_end");
  spec.h = optional_real(o, "h");
  spec.levels = static_cast<int>(o.integer("levels"));
  spec.refine = o.real("refine");
  spec.reference = o.text("reference");
  if (o.contains("reference_rtol")) spec.reference_rtol = o.real("reference_rtol");
  if (o.contains("reference_atol")) spec.reference_atol = o.real("reference_atol");
}

void ConvergenceSpec::validate() const {
  require_input(std::isfinite(t_end) && t_end > 0,
                "--t-end must be > 0 (got " + format_full(t_end) + ")");
  require_input(std::isnan(h) || h > 0, "--h must be > 0 (got " + format_full(h) + ")");
  validate_step_study();
}

nlohmann::json ConvergenceSpec::to_json() const { return step_study_json(); }

namespace {

enum class RefKind { exact, adaptive, fixed_step };

// What --reference, --reference-rtol and --reference-atol resolve to for one model.
struct ReferencePlan {
  RefKind kind = RefKind::exact;
  std::string method;
  Params params;  // the reference integrator's effective parameters (defaults filled in)
  double h = 0;   // step of a fixed-step reference
  std::string description;
};

bool declares(const std::vector<ParamSpec>& specs, const std::string& key) {
  for (const auto& p : specs)
    if (p.key == key) return true;
  return false;
}

// %.17g: the cache's number format (round-trips every double).
std::string g17(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

ReferencePlan plan_reference(const ConvergenceSpec& spec, const OdeSystem& sys, double h_finest) {
  ReferencePlan plan;
  const bool tol_given = spec.reference_rtol.has_value() || spec.reference_atol.has_value();
  const std::string tol_flag = spec.reference_rtol ? "--reference-rtol" : "--reference-atol";
  if (spec.reference == "exact" || (spec.reference == "auto" && sys.has_exact())) {
    require_input(sys.has_exact(), "--reference exact: model '" + sys.name() +
                                       "' has no exact solution (pass --reference METHOD, e.g. "
                                       "--reference cvode_bdf)");
    require_input(!tol_given, tol_flag +
                                  " applies to an adaptive --reference only: this study uses "
                                  "the exact solution of model '" +
                                  sys.name() +
                                  "' (omit it, or pass --reference cvode_bdf to compare against "
                                  "an adaptive run)");
    plan.description = "exact";
    return plan;
  }
  if (spec.reference == "auto") {
    throw BadInput("model '" + sys.name() +
                   "' has no exact solution: pass --reference METHOD (an adaptive integrator "
                   "such as cvode_bdf, run at --reference-rtol, default " +
                   format_full(ConvergenceSpec::kDefaultReferenceRtol) +
                   "; or a fixed-step one such as rk4, run at (finest h)/16)");
  }
  const auto* entry = integrator_registry().find(spec.reference);
  require_input(entry != nullptr, "--reference '" + spec.reference +
                                      "': neither 'exact' nor an integrator; known: " +
                                      join(integrator_registry().names()));
  plan.method = spec.reference;
  const std::string owner = "integrator '" + plan.method + "'";
  auto probe = integrator_registry().create(plan.method, spec.params);
  require_input(probe->supports_adaptive() || probe->supports_fixed_step(),
                "--reference '" + plan.method + "' has neither a fixed-step nor an adaptive mode");
  try {
    check_compatible(probe->info(), sys);
  } catch (const BadInput& e) {
    throw BadInput("--reference: " + std::string(e.what()));
  }
  if (probe->supports_adaptive()) {
    const double rtol = spec.reference_rtol.value_or(ConvergenceSpec::kDefaultReferenceRtol);
    const double atol = spec.reference_atol.value_or(rtol / ConvergenceSpec::kReferenceAtolDivisor);
    if (!declares(entry->params, "rtol") || !declares(entry->params, "atol"))
      throw std::logic_error(owner + " is adaptive but declares no rtol/atol parameters");
    Params user = spec.params;
    user.set("rtol", format_full(rtol));
    user.set("atol", format_full(atol));
    plan.kind = RefKind::adaptive;
    plan.params = resolve_params(entry->params, user, nullptr, owner);
    plan.description =
        plan.method + " adaptive, rtol = " + format_full(rtol) + ", atol = " + format_full(atol);
  } else {
    require_input(!tol_given, tol_flag + " applies to an adaptive --reference only: '" +
                                  plan.method +
                                  "' is fixed-step and runs at (finest h)/16 (omit it, or pass "
                                  "an adaptive reference such as --reference cvode_bdf)");
    plan.kind = RefKind::fixed_step;
    plan.h = h_finest / 16.0;
    plan.params = resolve_params(entry->params, spec.params, nullptr, owner);
    plan.description = plan.method + " with h = (finest h)/16 = " + format_full(plan.h);
  }
  return plan;
}

// y_ref at `times` (increasing, after t0), from the model's initial state.
std::vector<Vec> compute_reference(const ReferencePlan& plan, const OdeSystem& sys,
                                   const std::vector<double>& times) {
  std::vector<Vec> out;
  if (plan.kind == RefKind::exact) {
    for (double t : times) {
      Vec y(sys.dimension());
      sys.exact(t, y);
      out.push_back(y);
    }
    return out;
  }
  auto integ = integrator_registry().create(plan.method, plan.params);
  auto check = [&](const RunResult& r) {
    if (r.stats.status != Status::ok)
      throw std::runtime_error("reference run of '" + plan.method + "' (" + plan.description +
                               ") failed: " + to_string(r.stats.status) + " " + r.stats.message);
  };
  if (plan.kind == RefKind::adaptive) {
    AdaptiveOptions opt;
    opt.t_end = times.back();
    opt.times = times;
    long calls = 0;  // the first call is the initial state
    const RunResult r = run_adaptive(sys, *integ, opt, [&](double, CVecRef y) {
      if (calls++ > 0) out.emplace_back(y);
    });
    check(r);
    if (out.size() != times.size())
      throw std::logic_error("reference run returned " + std::to_string(out.size()) +
                             " states for " + std::to_string(times.size()) + " times");
    return out;
  }
  for (double t : times) {
    FixedStepOptions opt;
    opt.t_end = t;
    opt.h = plan.h;
    const RunResult r = run_fixed_step(sys, *integ, opt);
    check(r);
    out.push_back(r.y);
  }
  return out;
}

// Everything the reference values depend on, as one line of JSON (keys sorted).
// A fingerprint of the system's right-hand side, so that a changed f (a user's edited system
// under the same name, a model whose equations changed within one revision) never reuses a stale
// reference: f at three documented states — y0 at t0, and y0 + d and y0 - d/2 at t0 + 1/2 with
// d_i = 1e-3 (1 + |y0_i|) sin(i + 1) — and, where the model has one, the analytic Jacobian's
// values at y0 + d, hashed (FNV-1a) over the bytes of the doubles.
std::string system_fingerprint(const OdeSystem& sys) {
  const Vec y0 = sys.initial_state();
  const double t0 = sys.initial_time();
  Vec d(y0.size());
  for (Index i = 0; i < y0.size(); ++i)
    d[i] = 1e-3 * (1 + std::abs(y0[i])) * std::sin(static_cast<double>(i + 1));
  std::uint64_t h = kFnvOffset;
  auto add = [&h](const double* x, Index n) {
    h = fnv1a64(std::string_view(reinterpret_cast<const char*>(x),
                                 static_cast<std::size_t>(n) * sizeof(double)),
                h);
  };
  Vec f(y0.size());
  const std::vector<std::pair<double, Vec>> states = {
      {t0, y0}, {t0 + 0.5, y0 + d}, {t0 + 0.5, y0 - 0.5 * d}};
  try {
    for (const auto& [t, y] : states) {
      sys.rhs(t, y, f);
      add(f.data(), f.size());
    }
    if (sys.has_jacobian()) {
      SparseMat jac;
      sys.jacobian(t0 + 0.5, y0 + d, jac);
      jac.makeCompressed();
      add(jac.valuePtr(), static_cast<Index>(jac.nonZeros()));
    }
  } catch (const std::exception& e) {
    // A system that refuses one of these states is fingerprinted by what it said.
    h = fnv1a64(e.what(), h);
  }
  return hex16(h);
}

std::string cache_key(const ConvergenceSpec& spec, const OdeSystem& sys, const ReferencePlan& plan,
                      const std::vector<double>& times) {
  const Params model_params = resolve_params(model_registry().at(spec.model).params, spec.params,
                                             nullptr, "model '" + spec.model + "'");
  std::uint64_t y0_hash = kFnvOffset;
  const Vec y0 = sys.initial_state();
  for (Index i = 0; i < y0.size(); ++i) y0_hash = fnv1a64(g17(y0[i]) + ",", y0_hash);
  nlohmann::json key;
  key["cache_format"] = 2;  // 2: with the system's fingerprint
  key["stiffbench_version"] = STIFFBENCH_VERSION;
  key["git_revision"] = git_revision();
  key["model"] = spec.model;
  key["model_params"] = model_params.values();
  key["dimension"] = static_cast<long>(sys.dimension());
  key["initial_state_fnv1a"] = hex16(y0_hash);
  key["system_fingerprint"] = system_fingerprint(sys);
  key["reference"] = plan.method;
  key["mode"] = plan.kind == RefKind::adaptive ? "adaptive" : "fixed_step";
  key["reference_params"] = plan.params.values();
  if (plan.kind == RefKind::fixed_step) key["h"] = g17(plan.h);
  key["t0"] = g17(sys.initial_time());
  std::vector<std::string> ts;
  for (double t : times) ts.push_back(g17(t));
  key["times"] = ts;
  return key.dump();
}

// The cached values when `path` holds exactly this key and one complete row per time.
std::optional<std::vector<Vec>> read_cache(const std::filesystem::path& path,
                                           const std::string& key_line,
                                           const std::vector<double>& times, Index dim) {
  std::ifstream f(path);
  if (!f) return std::nullopt;
  std::string line;
  if (!std::getline(f, line) || line != key_line) return std::nullopt;
  while (std::getline(f, line) && !line.empty() && line[0] == '#') {
  }
  if (line.rfind("t,", 0) != 0) return std::nullopt;  // the column header
  std::vector<Vec> out;
  while (std::getline(f, line)) {
    if (line.empty()) continue;
    std::vector<double> v;
    const char* p = line.c_str();
    while (true) {
      char* end = nullptr;
      const double x = std::strtod(p, &end);
      if (end == p) return std::nullopt;
      v.push_back(x);
      p = end;
      if (*p == '\0') break;
      if (*p != ',') return std::nullopt;
      ++p;
    }
    if (out.size() >= times.size() || static_cast<Index>(v.size()) != dim + 1 ||
        v[0] != times[out.size()])
      return std::nullopt;
    Vec y(dim);
    for (Index i = 0; i < dim; ++i) y[i] = v[static_cast<std::size_t>(i) + 1];
    if (!y.allFinite()) return std::nullopt;
    out.push_back(y);
  }
  if (out.size() != times.size()) return std::nullopt;
  return out;
}

void write_cache(const std::filesystem::path& path, const std::string& key_line,
                 const std::string& readable, const std::vector<double>& times,
                 const std::vector<Vec>& values) {
  std::ostringstream os;
  os << key_line << "\n# " << readable << "\nt";
  for (Index i = 0; i < values.front().size(); ++i) os << ",y" << i;
  os << "\n";
  for (std::size_t k = 0; k < times.size(); ++k) {
    os << g17(times[k]);
    for (Index i = 0; i < values[k].size(); ++i) os << "," << g17(values[k][i]);
    os << "\n";
  }
  write_file_atomic(path, os.str());
}

struct ReferenceValues {
  std::vector<Vec> values;  // at the requested times, in their order
  std::string cache;
  bool from_cache = false;
};

// The reference at `times` (any order, duplicates allowed), through the cache when spec has a
// cache_dir and the reference is not exact.
ReferenceValues reference_values(const ConvergenceSpec& spec, const OdeSystem& sys,
                                 const ReferencePlan& plan, std::vector<double> times,
                                 std::ostream* progress) {
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  ReferenceValues res;
  std::vector<Vec> values;
  const bool use_cache = plan.kind != RefKind::exact && !spec.cache_dir.empty();
  std::filesystem::path path;
  std::string key_line;
  if (use_cache) {
    key_line = "# key: " + cache_key(spec, sys, plan, sorted);
    path =
        std::filesystem::path(spec.cache_dir) / "reference" / (hex16(fnv1a64(key_line)) + ".csv");
    res.cache = path.string();
    if (auto cached = read_cache(path, key_line, sorted, sys.dimension())) {
      values = std::move(*cached);
      res.from_cache = true;
      if (progress) *progress << "reference: cached " << path.string() << "\n";
    } else if (progress && std::filesystem::exists(path)) {
      *progress << "reference: " << path.string()
                << " does not match this reference; recomputing\n";
    }
  }
  if (!res.from_cache) {
    const auto start = std::chrono::steady_clock::now();
    values = compute_reference(plan, sys, sorted);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (use_cache) {
      std::ostringstream readable;
      readable << "model " << spec.model;
      for (const auto& [k, v] : spec.params.values()) readable << " " << k << "=" << v;
      readable << "; reference " << plan.description << "; t0 = " << g17(sys.initial_time())
               << ", t_end = " << g17(sorted.back()) << ", " << sorted.size()
               << " reference time(s); computed in " << format_short(wall, 2) << " s";
      write_cache(path, key_line, readable.str(), sorted, values);
      if (progress)
        *progress << "reference: computed " << plan.description << " in " << format_short(wall, 2)
                  << " s; wrote " << path.string() << "\n";
    } else if (progress && plan.kind != RefKind::exact) {
      *progress << "reference: computed " << plan.description << " in " << format_short(wall, 2)
                << " s\n";
    }
  }
  for (double t : times) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), t);
    res.values.push_back(values[static_cast<std::size_t>(it - sorted.begin())]);
  }
  return res;
}

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

// The user's parameters without those only a --reference integrator declares (it takes them;
// make_setup would call them unknown). A key the model or a studied integrator also declares
// stays, so it reaches them as well.
Params setup_params(const ConvergenceSpec& spec) {
  const auto* ref = integrator_registry().find(spec.reference);
  if (!ref) return spec.params;
  auto declared_elsewhere = [&](const std::string& key) {
    if (declares(model_registry().at(spec.model).params, key)) return true;
    for (const auto& name : spec.integrators)
      if (declares(integrator_registry().at(name).params, key)) return true;
    return false;
  };
  Params out;
  for (const auto& [key, value] : spec.params.values())
    if (!declares(ref->params, key) || declared_elsewhere(key)) out.set(key, value);
  return out;
}

ConvergenceResult run_study(const ConvergenceSpec& given, std::ostream* progress, bool local) {
  given.validate();
  Setup setup = make_setup(given.model, given.integrators, setup_params(given));
  const OdeSystem& sys = *setup.model;
  ConvergenceSpec spec = given;
  const Resolved h0 = resolve_step(sys, spec.h, spec.model);
  spec.h = h0.value;
  const std::string h_source = h0.source;
  if (progress && h0.source != "--h")
    *progress << "no --h given: starting from the model's suggested step h = "
              << format_full(spec.h) << " (" << h0.source.substr(16) << ")\n";
  const double t0 = sys.initial_time();
  require_input(spec.t_end > t0, "--t-end must be > the model's initial time");
  for (const auto& integ : setup.integrators)
    require_input(
        integ->supports_fixed_step(),
        "integrator '" + integ->info().name +
            "' is adaptive only: a step-size study needs fixed steps (use work-precision)");

  // Actual step sizes are fixed by the driver's N = round(T/h) rule (global study); the local
  // study uses h_k exactly.
  const std::vector<double> hs = spec.step_ladder(spec.h);
  for (double h : hs) fixed_step_count(t0, spec.t_end, h, FixedStepOptions{}.max_steps);

  const ReferencePlan plan = plan_reference(spec, sys, hs.back());
  if (!spec.cache_dir.empty() && plan.kind != RefKind::exact) require_output_dir(spec.cache_dir);
  ConvergenceResult result;
  result.reference_description = plan.description;
  result.h = spec.h;
  result.h_source = h_source;

  // Per level for local, one value for global.
  std::vector<double> ref_times;
  if (local) {
    for (double h : hs) ref_times.push_back(t0 + h);
  } else {
    ref_times.push_back(spec.t_end);
  }
  ReferenceValues ref = reference_values(spec, sys, plan, ref_times, progress);
  result.reference_cache = ref.cache;
  result.reference_from_cache = ref.from_cache;
  const std::vector<Vec>& ref_values = ref.values;

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
      row.steps = r.stats.steps;  // the steps taken: N unless the run ended early
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
  std::vector<double> lh, le;
  for (const auto& r : rows)
    if (r.integrator == integrator && r.stats.status == Status::ok && r.error > 0) {
      lh.push_back(std::log(r.h));
      le.push_back(std::log(r.error));
    }
  const std::size_t n = std::min(lh.size(), static_cast<std::size_t>(points));
  return least_squares_slope(std::vector<double>(lh.end() - n, lh.end()),
                             std::vector<double>(le.end() - n, le.end()));
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
     << "; reference: " << res.reference_description;
  if (!res.reference_cache.empty())
    os << " (values in `reference/"
       << std::filesystem::path(res.reference_cache).filename().string() << "`"
       << (res.reference_from_cache ? ", reused from an earlier run" : "") << ")";
  os << ".";
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
  std::vector<RunNote> notes;
  for (const auto& r : res.rows)
    notes.push_back({r.integrator + ", h = " + format_short(r.h), &r.stats});
  os << failed_runs_markdown(notes);
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
  // "spec" is the spec as given (what check_study_output compares before a run); the step it
  // resolved to is recorded beside it.
  nlohmann::json meta = run_metadata(local ? "local-error" : "convergence", spec.to_json());
  add_step_study_metadata(meta, res.h, res.h_source, res.reference_description);
  if (!res.reference_cache.empty()) {
    meta["reference_cache"] = res.reference_cache;
    meta["reference_from_cache"] = res.reference_from_cache;
  }
  meta["error_norm"] = "max-norm of the absolute error";
  write_file_atomic(d / (name + ".json"), meta.dump(2) + "\n");
}

Vec reference_at_end(const StepStudySpec& spec, const OdeSystem& sys, double t_end, double h_fine,
                     std::string* description) {
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
  if (declares(entry.params, "rtol")) {
    p.set("rtol", format_full(spec.reference_rtol.value_or(1e-14)));
    p.set("atol", format_full(spec.reference_atol.value_or(1e-16)));
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

namespace {

// convergence and local-error in the study registry.
class ConvergenceJob : public StudyJob {
 public:
  ConvergenceJob(ConvergenceSpec spec, bool local) : spec_(std::move(spec)), local_(local) {
    spec_.validate();
  }
  nlohmann::json spec_json() const override { return spec_.to_json(); }
  std::vector<std::string> helper_integrators() const override {
    return spec_.reference_integrators();
  }
  void run(std::ostream* progress) override {
    result_ = local_ ? run_local_error(spec_, progress) : run_convergence(spec_, progress);
  }
  Table unit_table() const override {
    return local_ ? local_error_table(result_) : convergence_table(result_);
  }
  bool write(const std::filesystem::path& dir, const std::string& title, const PlotOptions& plot,
             std::ostream& err) const override {
    write_convergence_outputs(dir.string(), name(), spec_, result_, local_);
    return plot_convergence(dir / (name() + ".csv"), title, local_, plot, err);
  }
  void print_summary(std::ostream& out) const override { out << unit_table().to_markdown(); }
  std::string report_markdown(const std::string& note) const override {
    std::ostringstream md;
    md << note << " Reference: " << result_.reference_description << ".\n\n";
    Table summary{{"integrator", local_ ? "expected slope" : "order", "last observed order",
                   "status of finest run"},
                  {}};
    for (const auto& integ : spec_.integrators) {
      const auto last = last_observed_order(result_.rows, integ);
      std::string status;
      int order = 0;
      for (const auto& r : result_.rows)
        if (r.integrator == integ) {
          status = to_string(r.stats.status);
          order = r.order + (local_ ? 1 : 0);
        }
      summary.rows.push_back(
          {integ, std::to_string(order), last ? format_fixed(*last) : "-", status});
    }
    md << summary.to_markdown() << "\n";
    return md.str();
  }
  std::string default_title() const override {
    return (local_ ? "Local error: " : "Global error: ") + spec_.model;
  }
  const ConvergenceResult& result() const { return result_; }

 private:
  std::string name() const { return local_ ? "local_error" : "convergence"; }
  ConvergenceSpec spec_;
  bool local_;
  ConvergenceResult result_;
};

StudyKind step_size_kind(bool local) {
  StudyKind k;
  k.name = local ? "local-error" : "convergence";
  k.stem = local ? "local_error" : "convergence";
  k.summary = local ? "error of one step from the initial state against h; writes "
                      "local_error.{csv,md,json}"
                    : "global error at t_end against h = H/refine^k; writes "
                      "convergence.{csv,md,json}";
  StepStudyDefaults d;
  d.t_end_help = local ? "unused by the local study's error; kept for symmetry" : "final time";
  d.h_help = "coarsest step size (default: the model's suggested step, where it has one)";
  d.ref_help =
      "exact | METHOD: an adaptive integrator (cvode_bdf, cvode_adams, arkode_*, gsl_*) runs at "
      "--reference-rtol/--reference-atol and stops exactly at the reference times; a fixed-step "
      "one (e.g. rk4) runs at (finest h)/16. Default: exact where the model has one; a model "
      "without one needs --reference. A non-exact reference is cached in OUT/reference/<hash>.csv "
      "and reused by a run of the same build with the same model, parameters, reference and "
      "times";
  k.options = step_study_options(d);
  for (auto& o : k.options) {
    if (o.key == "reference_rtol") o.help += " (default 1e-12)";
    if (o.key == "reference_atol") o.help += " (default rtol/100)";
  }
  if (!local) k.required = {"t_end"};
  k.unit_columns =
      (local ? local_error_table(ConvergenceResult{}) : convergence_table(ConvergenceResult{}))
          .columns;
  k.make = [local](const StudyTarget& t, const Params& o, const StudyContext& ctx) {
    ConvergenceSpec spec;
    spec.model = t.model;
    spec.params = t.params;
    spec.integrators = t.integrators;
    read_step_study_options(o, spec);
    spec.cache_dir = ctx.cache_dir;
    return std::make_unique<ConvergenceJob>(std::move(spec), local);
  };
  return k;
}

}  // namespace

StudyKind convergence_study_kind() { return step_size_kind(false); }
StudyKind local_error_study_kind() { return step_size_kind(true); }

const ConvergenceResult& convergence_result(const StudyJob& job) {
  return dynamic_cast<const ConvergenceJob&>(job).result();
}

ConvergenceResult convergence_study(ConvergenceSpec spec, const std::string& dir, bool local,
                                    std::ostream* progress, std::ostream& err,
                                    const PlotOptions& plot) {
  StudyContext ctx;
  ctx.force = force_output();
  ctx.plot = plot;
  ctx.progress = progress;
  ctx.err = &err;
  return convergence_study(std::move(spec), StudyObjects{}, dir, local, ctx);
}

ConvergenceResult convergence_study(ConvergenceSpec spec, const StudyObjects& objects,
                                    const std::filesystem::path& dir, bool local,
                                    const StudyContext& ctx) {
  const ScopedStudyObjects scope(objects, spec.model, spec.integrators);
  if (spec.cache_dir.empty()) spec.cache_dir = ctx.cache_dir.empty() ? dir.string() : ctx.cache_dir;
  ConvergenceJob job(std::move(spec), local);
  run_study_job(study_kind(local ? "local-error" : "convergence"), job, dir, ctx);
  return job.result();
}

ConvergenceResult run_convergence(ConvergenceSpec spec, const StudyObjects& objects,
                                  std::ostream* progress) {
  const ScopedStudyObjects scope(objects, spec.model, spec.integrators);
  return run_convergence(static_cast<const ConvergenceSpec&>(spec), progress);
}

ConvergenceResult run_local_error(ConvergenceSpec spec, const StudyObjects& objects,
                                  std::ostream* progress) {
  const ScopedStudyObjects scope(objects, spec.model, spec.integrators);
  return run_local_error(static_cast<const ConvergenceSpec&>(spec), progress);
}

ConvergenceResult run_convergence(ConvergenceSpec spec, const SystemFactory& system,
                                  std::ostream* progress) {
  return run_convergence(std::move(spec), StudyObjects{system, {}}, progress);
}

ConvergenceResult run_local_error(ConvergenceSpec spec, const SystemFactory& system,
                                  std::ostream* progress) {
  return run_local_error(std::move(spec), StudyObjects{system, {}}, progress);
}

}  // namespace stiffbench

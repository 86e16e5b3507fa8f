#include "experiments/studies/convergence.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/support/coefficients.hpp"

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

std::optional<double> ConvergenceSpec::given_floor() const {
  if (floor == "auto" || floor == "model") return std::nullopt;
  std::size_t used = 0;
  double v = std::numeric_limits<double>::quiet_NaN();
  try {
    v = std::stod(floor, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  require_input(!floor.empty() && used == floor.size() && std::isfinite(v) && v > 0,
                "--floor must be auto, model or a positive number (got '" + floor + "')");
  return v;
}

void ConvergenceSpec::validate() const {
  require_input(std::isfinite(t_end) && t_end > 0,
                "--t-end must be > 0 (got " + format_full(t_end) + ")");
  require_input(std::isnan(h) || h > 0, "--h must be > 0 (got " + format_full(h) + ")");
  validate_step_study();
  require_input(ladder == "common" || ladder == "per-method",
                "--ladder must be common or per-method (got '" + ladder + "')");
  given_floor();
}

nlohmann::json ConvergenceSpec::to_json() const {
  nlohmann::json j = step_study_json();
  j["ladder"] = ladder;
  j["floor"] = floor;
  return j;
}

namespace {

// splitmix64 (Steele, Lea & Flood, OOPSLA 2014): the perturbations' deterministic generator.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

Vec perturbed_initial_state(const Vec& y0, int sign) {
  std::uint64_t state = kFloorSeed;
  Vec y = y0;
  // y0 = 0: every component moves by ±kFloorPerturbation (absolute: the solution's scale 1).
  const bool all_zero = !(y0.array() != 0.0).any();
  for (Index i = 0; i < y.size(); ++i) {
    // One draw per component, zero or not, so a component's sign depends on its index only.
    const std::uint64_t r = splitmix64(state);
    const double s = ((r >> 32) & 1U) != 0 ? 1.0 : -1.0;
    if (all_zero)
      y[i] = sign * s * kFloorPerturbation;
    else if (y[i] != 0 && std::isfinite(y[i]))
      y[i] *= 1 + sign * s * kFloorPerturbation;
  }
  return y;
}

std::optional<double> measure_roundoff_floor(
    const Vec& y0, const Vec& y, const std::function<std::optional<Vec>(const Vec&)>& run,
    std::vector<double>* spreads) {
  const std::optional<Vec> up = run(perturbed_initial_state(y0, 1));
  const std::optional<Vec> down = run(perturbed_initial_state(y0, -1));
  auto usable = [&](const std::optional<Vec>& v) {
    return v && v->size() == y.size() && v->allFinite();
  };
  if (!usable(up) || !usable(down)) return std::nullopt;
  const double d = (0.5 * (*up + *down) - y).cwiseAbs().maxCoeff();
  if (spreads) {
    spreads->push_back(max_abs_diff(*up, y));
    spreads->push_back(max_abs_diff(*down, y));
    spreads->push_back(d);
  }
  return std::max(kFloorSecondDifferenceFactor * d,
                  kUnitRoundoff * (y.size() ? y.cwiseAbs().maxCoeff() : 0.0));
}

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

// %g: the documented constants in sentences (10, 0.2, 0.01).
std::string g_short(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", x);
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
    // At most (t - t0)/16, so a per-method local ladder finer than the common one still gets a
    // reference 16 times finer than its step (the common ladder's times are unaffected).
    opt.h = std::min(plan.h, (t - sys.initial_time()) / 16.0);
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
  key["cache_format"] = 3;  // 2: with the system's fingerprint; 3: with its content's hash
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

// A cache file: line 1 "# key: KEY", line 2 "# readable description", line 3 "# content: N
// rows, fnv1a64 HASH" (of every line below it, each with its newline), then the column header
// and one row per time.
std::string content_line(const std::string& data, std::size_t rows) {
  return "# content: " + std::to_string(rows) + " rows, fnv1a64 " + hex16(fnv1a64(data));
}

// The cached values when `path` holds exactly this key, its data match the recorded hash and row
// count (a truncated or edited file does not), and there is one complete row per time;
// otherwise why not, in `why`.
std::optional<std::vector<Vec>> read_cache(const std::filesystem::path& path,
                                           const std::string& key_line,
                                           const std::vector<double>& times, Index dim,
                                           std::string& why) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return std::nullopt;
  const std::string text{std::istreambuf_iterator<char>(f), {}};
  std::istringstream in(text);
  std::string line, readable, content;
  why = "does not match this reference";
  if (!std::getline(in, line) || line != key_line) return std::nullopt;
  if (!std::getline(in, readable) || !std::getline(in, content) ||
      content.rfind("# content: ", 0) != 0) {
    why = "records no content hash";
    return std::nullopt;
  }
  const auto data_start = static_cast<std::size_t>(in.tellg());
  const std::string data = data_start <= text.size() ? text.substr(data_start) : "";
  if (content != content_line(data, times.size())) {
    why = "does not hold what it recorded (" + content.substr(2) + "): truncated or edited";
    return std::nullopt;
  }
  why = "does not match this reference";
  if (!std::getline(in, line) || line.rfind("t,", 0) != 0) return std::nullopt;  // the header
  std::vector<Vec> out;
  while (std::getline(in, line)) {
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
  std::ostringstream data;
  data << "t";
  for (Index i = 0; i < values.front().size(); ++i) data << ",y" << i;
  data << "\n";
  for (std::size_t k = 0; k < times.size(); ++k) {
    data << g17(times[k]);
    for (Index i = 0; i < values[k].size(); ++i) data << "," << g17(values[k][i]);
    data << "\n";
  }
  write_file_atomic(path, key_line + "\n# " + readable + "\n" +
                              content_line(data.str(), times.size()) + "\n" + data.str());
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
    std::string why;
    if (auto cached = read_cache(path, key_line, sorted, sys.dimension(), why)) {
      values = std::move(*cached);
      res.from_cache = true;
      if (progress) *progress << "reference: cached " << path.string() << "\n";
    } else if (progress && std::filesystem::exists(path)) {
      *progress << "reference: " << path.string() << " " << why << "; recomputing\n";
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

// The second reference run: tolerances / kReferenceTightening for an adaptive reference, half
// the step for a fixed-step one.
ReferencePlan tighter_plan(const ReferencePlan& plan) {
  ReferencePlan t = plan;
  if (plan.kind == RefKind::adaptive) {
    const double rtol = plan.params.real("rtol") / kReferenceTightening;
    const double atol = plan.params.real("atol") / kReferenceTightening;
    t.params.set("rtol", format_full(rtol));
    t.params.set("atol", format_full(atol));
    t.description =
        plan.method + " adaptive, rtol = " + format_full(rtol) + ", atol = " + format_full(atol);
  } else if (plan.kind == RefKind::fixed_step) {
    t.h = plan.h / 2;
    t.description = plan.method + " with h = " + format_full(t.h);
  }
  return t;
}

double inf_norm(CVecRef y) { return y.size() ? y.cwiseAbs().maxCoeff() : 0.0; }

// Stage 1 of the per-method probe: what the probes found about the target error.
struct ProbeBracket {
  double h_below = 0, h_above = 0;  // bracket: error below / above the target
  double e_below = 0, e_above = 0;
  bool floor_hit = false;
  double h_hint = 0;  // set when a probe lands just above the target
};

using ProbeFn = std::function<double(double)>;

// Stage 1: from h, towards the coarsest step allowed, where the error is about `target`, while
// fewer than kProbeRuns - 2 runs (counted in `runs` by `probe`) have been made.
ProbeBracket probe_coarsest(double h, double lo, double hi, double target, int q, const int& runs,
                            const ProbeFn& probe, const ProbeFn& floor_at) {
  ProbeBracket b;
  const int stage1_runs = kProbeRuns - 2;
  while (runs < stage1_runs) {
    const double e = probe(h);
    double next;
    if (std::isfinite(e) && e > target && e <= 2 * target && e > kFloorFactor * floor_at(h)) {
      // Within a factor 2 above the target: close enough; the step e ∝ h^p gives the target.
      b.h_hint = h * std::pow(target / e, 1.0 / q);
      break;
    }
    if (!std::isfinite(e) || e > target) {
      if (!(b.h_above > 0) || h < b.h_above) {
        b.h_above = h;
        b.e_above = std::isfinite(e) ? e : 0;
      }
      if (h <= lo) break;
      next = std::max(lo, h / 4);
    } else if (e <= kFloorFactor * floor_at(h)) {
      b.floor_hit = true;
      b.h_below = std::max(b.h_below, h);
      b.e_below = 0;
      if (h >= hi) break;
      next = std::min(hi, h * 4);
    } else {
      b.h_below = h;
      b.e_below = e;
      if (e > target / 3) break;  // within a factor 3 below the target: close enough
      if (h >= hi) break;
      next = std::min(hi, h * std::pow(target / e, 1.0 / q));
    }
    // Inside a bracket: interpolate in log-log when both ends have errors, else bisect.
    if (b.h_below > 0 && b.h_above > 0) {
      if (b.e_below > 0 && b.e_above > 0)
        next = b.h_below * std::exp(std::log(b.h_above / b.h_below) * std::log(target / b.e_below) /
                                    std::log(b.e_above / b.e_below));
      else
        next = std::sqrt(b.h_below * b.h_above);
      next = std::clamp(next, std::min(b.h_below, b.h_above), std::max(b.h_below, b.h_above));
    }
    if (std::abs(next - h) <= 0.02 * h) break;  // no progress (e.g. the same step count)
    h = next;
  }
  return b;
}

// h_top: the largest usable probe at or below the target, else the model's prediction.
double top_step(const ProbeBracket& b, const std::vector<std::pair<double, double>>& good,
                double target, double lo, double hi, int q) {
  double h_top = 0;
  for (const auto& [gh, ge] : good)
    if (ge <= target) h_top = std::max(h_top, gh);
  if (!(h_top > 0)) h_top = std::clamp(b.h_below > 0 ? b.h_below : lo, lo, hi);
  if (b.h_hint > 0) h_top = std::clamp(std::max(h_top, b.h_hint), lo, hi);
  if (b.h_hint == 0 && b.e_below > 0 && b.e_below < target / 3) {
    const double predicted = b.h_below * std::pow(target / b.e_below, 1.0 / q);
    // Never at or beyond a step whose run failed or overshot the target.
    if (!(b.h_above > 0) || predicted < b.h_above) h_top = std::min(hi, std::max(h_top, predicted));
  }
  return h_top;
}

// Stage 2: the ladder moves down (at most by its own length span = h0/h_finest, not below lo)
// from h_top until its finest error is about kLadderFloorMargin times the floors: the most
// asymptotic levels. Returns h0.
double probe_finest(double h_top, double lo, double span, int q, const int& runs,
                    const ProbeFn& probe, const ProbeFn& predict, const ProbeFn& floor_at,
                    const std::function<void(double)>& calibrate) {
  const double h0_min = std::max(lo, h_top / span);
  const double fine_lo = h0_min / span, fine_hi = h_top / span;
  double h_fine = fine_hi;
  if (calibrate) calibrate(fine_hi);
  auto fine_target = [&](double hf) { return kLadderFloorMargin * floor_at(hf); };
  if (predict(h_fine) <= fine_target(h_fine)) return h_top;  // already reaches the floor region
  for (int it = 0; it < 3; ++it)
    h_fine = std::clamp(h_fine * std::pow(fine_target(h_fine) / predict(h_fine), 1.0 / q), fine_lo,
                        fine_hi);
  while (runs < kProbeRuns) {
    const double e = probe(h_fine);
    if (!std::isfinite(e)) break;
    const double ratio = fine_target(h_fine) / std::max(e, 1e-300);
    if (std::abs(std::log(ratio)) <= std::log(3.0)) break;
    const double next =
        std::clamp(h_fine * std::clamp(std::pow(ratio, 1.0 / q), 1.0 / 16, 16.0), fine_lo, fine_hi);
    if (next == h_fine) break;
    h_fine = next;
  }
  return std::clamp(h_fine * span, h0_min, h_top);
}

// The per-method probe (see the header): the coarsest step of one integrator's ladder.
// error_at(h): the error of a run at h (NaN when it failed); floor_at(h): the larger floor of a
// run at h; q: the expected slope. calibrate(h), when set, is called once before stage 2 with the
// finest step of the coarsest allowed ladder (--floor auto measures the round-off floor there,
// which floor_at then uses).
double probe_ladder(const ConvergenceSpec& spec, double t_span, bool local, double s, int q,
                    const std::function<double(double)>& error_at,
                    const std::function<double(double)>& floor_at,
                    const std::function<void(double)>& calibrate,
                    ConvergenceResult::Ladder& record) {
  const double target = kLadderTop * s;
  // Not below h/64, nor so small that the finest level would exceed the driver's step limit.
  const double span = std::pow(spec.refine, spec.levels - 1);  // h0 / h_finest
  const double lo = std::max(
      spec.h / 64, local ? 0.0 : t_span * span / static_cast<double>(FixedStepOptions{}.max_steps));
  const double hi = std::max(lo, local ? 16 * spec.h : std::min(16 * spec.h, t_span / 4));
  int runs = 0;
  // The usable probes (finite, above the floors): (h, error).
  std::vector<std::pair<double, double>> good;
  auto probe = [&](double h) {
    ++runs;
    const double e = error_at(h);
    record.probes.emplace_back(h, e);
    const bool usable = std::isfinite(e) && e > kFloorFactor * floor_at(h);
    if (usable) good.emplace_back(h, e);
    return e;
  };
  // The error model through the usable probe nearest to h (in log h): e ∝ h^q.
  auto predict = [&](double h) {
    const auto* best = &good.front();
    for (const auto& g : good)
      if (std::abs(std::log(g.first / h)) < std::abs(std::log(best->first / h))) best = &g;
    return best->second * std::pow(h / best->first, q);
  };
  const ProbeBracket b =
      probe_coarsest(std::clamp(spec.h, lo, hi), lo, hi, target, q, runs, probe, floor_at);
  if (good.empty()) return b.floor_hit ? hi : lo;
  const double h_top = top_step(b, good, target, lo, hi, q);
  return probe_finest(h_top, lo, span, q, runs, probe, predict, floor_at, calibrate);
}

// One convergence or local-error study in progress: the system, its initial state, the reference
// plan and its check, and the reference values once computed. run_step_study's steps share it.
struct StudyState {
  const ConvergenceSpec& spec;
  const OdeSystem& sys;
  bool local;
  std::ostream* progress;
  double t0 = 0;
  Vec y0;
  double y0_norm = 0;
  ReferencePlan plan, plan2;
  bool numerical_ref = false;
  Vec ref_end;                             // global: the reference at t_end
  double ref_acc_end = 0;                  // global: its accuracy from the check run (0: none)
  double s_end = 1;                        // the solution's size for the round-off floor
  std::vector<Vec> ref_local, ref2_local;  // local: references at every t0 + h, and the check's

  StudyState(const ConvergenceSpec& s, const OdeSystem& system, bool is_local, std::ostream* out)
      : spec(s), sys(system), local(is_local), progress(out) {}

  std::optional<double> given_floor;  // --floor VALUE

  RunResult run_at(Integrator& integ, double h) const { return run_from(integ, h, y0); }
  RunResult run_from(Integrator& integ, double h, const Vec& start) const {
    FixedStepOptions opt;
    opt.t_end = local ? t0 + h : spec.t_end;
    opt.h = h;
    return run_fixed_step_from(sys, integ, t0, start, opt);
  }
  // The model round-off floor N·u·s of a run at h (u·s for the local error).
  double model_floor(double h) const {
    if (local) return kUnitRoundoff * std::max(1.0, y0_norm);
    return static_cast<double>(step_count(h)) * kUnitRoundoff * s_end;
  }
  long step_count(double h) const {
    return local ? 1 : fixed_step_count(t0, spec.t_end, h, FixedStepOptions{}.max_steps);
  }
  // --floor auto: the measured round-off floor of `integ` at step h (measure_roundoff_floor),
  // `y` the unperturbed run's final state; empty when it cannot be measured.
  std::optional<double> measured_floor(Integrator& integ, double h, const Vec& y,
                                       std::vector<double>* spreads) const {
    return measure_roundoff_floor(
        y0, y,
        [&](const Vec& start) -> std::optional<Vec> {
          const RunResult r = run_from(integ, h, start);
          if (r.stats.status != Status::ok) return std::nullopt;
          return r.y;
        },
        spreads);
  }
};

// The reference check run (plan2) at `times`; empty when it fails (a tolerance the reference
// cannot meet), which leaves the study without a reference floor and says so.
std::optional<ReferenceValues> reference_check(StudyState& st, const std::vector<double>& times,
                                               ConvergenceResult& result) {
  try {
    ReferenceValues ref2 = reference_values(st.spec, st.sys, st.plan2, times, st.progress);
    result.reference_check_cache = ref2.cache;
    return ref2;
  } catch (const std::runtime_error& e) {
    result.reference_check_description += " (failed: " + std::string(e.what()) + ")";
    if (st.progress) *st.progress << "reference check: " << e.what() << "\n";
    return std::nullopt;
  }
}

// The global study's reference at t_end and its check (the probes need them first).
void global_reference(StudyState& st, ConvergenceResult& result) {
  ReferenceValues ref = reference_values(st.spec, st.sys, st.plan, {st.spec.t_end}, st.progress);
  result.reference_cache = ref.cache;
  result.reference_from_cache = ref.from_cache;
  st.ref_end = ref.values[0];
  if (!st.numerical_ref) return;
  if (const auto ref2 = reference_check(st, {st.spec.t_end}, result)) {
    st.ref_acc_end = max_abs_diff(st.ref_end, ref2->values[0]);
    result.reference_accuracy = st.ref_acc_end;
  }
}

// The local study's reference (and its check) at every t0 + h of every ladder.
void local_references(StudyState& st, const std::vector<std::vector<double>>& ladders,
                      ConvergenceResult& result) {
  std::vector<double> ref_times;
  for (const auto& ladder : ladders)
    for (double h : ladder) ref_times.push_back(st.t0 + h);
  ReferenceValues ref = reference_values(st.spec, st.sys, st.plan, ref_times, st.progress);
  result.reference_cache = ref.cache;
  result.reference_from_cache = ref.from_cache;
  st.ref_local = std::move(ref.values);
  if (!st.numerical_ref) return;
  if (auto ref2 = reference_check(st, ref_times, result)) {
    st.ref2_local = std::move(ref2->values);
    double worst = 0;
    for (std::size_t k = 0; k < st.ref_local.size(); ++k)
      worst = std::max(worst, max_abs_diff(st.ref_local[k], st.ref2_local[k]));
    result.reference_accuracy = worst;
  }
}

// Per-method ladders: each integrator's h0 from a short probe (probe_ladder), recorded in
// result.ladders.
std::vector<std::vector<double>> per_method_ladders(const StudyState& st, Setup& setup,
                                                    ConvergenceResult& result) {
  const ConvergenceSpec& spec = st.spec;
  const bool local = st.local;
  std::vector<std::vector<double>> ladders;
  for (auto& integ_ptr : setup.integrators) {
    Integrator& integ = *integ_ptr;
    ConvergenceResult::Ladder rec;
    rec.integrator = integ.info().name;
    const int q = std::max(1, integ.info().order + (local ? 1 : 0));
    auto error_at = [&](double h) {
      const RunResult r = st.run_at(integ, h);
      if (r.stats.status != Status::ok) return std::numeric_limits<double>::quiet_NaN();
      if (!local) return max_abs_diff(r.y, st.ref_end);
      // The probe's local reference is computed directly (uncached): one short run.
      return max_abs_diff(r.y, compute_reference(st.plan, st.sys, {st.t0 + h})[0]);
    };
    // The round-off floor of the probe: given, measured once (calibrate; in proportion to the
    // steps below the measured step) or the model.
    std::optional<double> measured;
    double measured_steps = 1;
    auto roundoff_at = [&](double h) {
      if (st.given_floor) return *st.given_floor;
      if (measured)
        return *measured * std::max(1.0, static_cast<double>(st.step_count(h)) / measured_steps);
      return st.model_floor(h);
    };
    auto floor_at = [&](double h) {
      return local ? roundoff_at(h) : std::max(roundoff_at(h), st.ref_acc_end);
    };
    std::function<void(double)> calibrate;
    if (spec.floor == "auto")
      calibrate = [&](double h) {
        const RunResult r = st.run_at(integ, h);
        if (r.stats.status != Status::ok) return;
        std::vector<double> spreads;
        if (const auto f = st.measured_floor(integ, h, r.y, &spreads)) {
          measured = *f;
          measured_steps = static_cast<double>(st.step_count(h));
          rec.floor_h = h;
          rec.floor = *f;
        }
      };
    rec.h0 =
        probe_ladder(spec, spec.t_end - st.t0, local, local ? std::max(1.0, st.y0_norm) : st.s_end,
                     q, error_at, floor_at, calibrate, rec);
    ladders.push_back(spec.step_ladder(rec.h0));
    for (double h : ladders.back())
      fixed_step_count(st.t0, spec.t_end, h, FixedStepOptions{}.max_steps);
    if (st.progress)
      *st.progress << "ladder: " << rec.integrator << " h0 = " << format_short(rec.h0) << " after "
                   << rec.probes.size() << " probe run(s)\n";
    result.ladders.push_back(std::move(rec));
  }
  return ladders;
}

// One row: the run at h, its error against the reference (index ref_index of the local ones)
// and its model and reference floors (the round-off floor in use comes later: apply_floor).
// `y_end` receives the run's final state.
ConvergenceRow measure_row(const StudyState& st, Integrator& integ, double h, std::size_t ref_index,
                           const ConvergenceResult& result, Vec& y_end) {
  ConvergenceRow row;
  row.model = st.spec.model;
  row.integrator = integ.info().name;
  row.order = integ.info().order;
  const RunResult r = st.run_at(integ, h);
  y_end = r.y;
  row.h = r.h;
  row.steps = r.stats.steps;  // the steps taken: N unless the run ended early
  row.stats = r.stats;
  const Vec& yref = st.local ? st.ref_local[ref_index] : st.ref_end;
  row.error = r.stats.status == Status::ok ? max_abs_diff(r.y, yref)
                                           : std::numeric_limits<double>::quiet_NaN();
  const double s = std::max({1.0, st.y0_norm, inf_norm(yref)});
  row.roundoff_floor =
      (st.local ? 1.0 : static_cast<double>(std::max(1L, row.steps))) * kUnitRoundoff * s;
  if (st.numerical_ref && result.reference_accuracy)
    row.reference_floor =
        st.local ? max_abs_diff(st.ref_local[ref_index], st.ref2_local[ref_index]) : st.ref_acc_end;
  return row;
}

// The round-off floor of one integrator's rows (--floor): given, the model, or measured by
// perturbed reruns at its finest level that ran ok (`finest_y`: each level's final state).
ConvergenceResult::Floor integrator_floor(const StudyState& st, Integrator& integ,
                                          const std::vector<ConvergenceRow>& rows,
                                          const std::vector<Vec>& finals) {
  ConvergenceResult::Floor fl;
  fl.integrator = integ.info().name;
  if (st.given_floor) {
    fl.value = *st.given_floor;
    fl.source = "given";
    return fl;
  }
  fl.source = "model";
  fl.value = rows.empty() ? 0.0 : rows.back().roundoff_floor;
  if (st.spec.floor == "model") return fl;
  std::size_t finest = rows.size();
  for (std::size_t k = 0; k < rows.size(); ++k)
    if (rows[k].stats.status == Status::ok) finest = k;
  if (finest == rows.size()) {
    fl.note = "no level ran ok: nothing to measure";
    return fl;
  }
  const auto measured = st.measured_floor(integ, rows[finest].h, finals[finest], &fl.spreads);
  fl.h = rows[finest].h;
  fl.steps = std::max(1L, rows[finest].steps);
  if (!measured) {
    fl.note = "a perturbed rerun did not end ok";
    return fl;
  }
  fl.value = *measured;
  fl.source = "perturbed";
  return fl;
}

// The floor in use for a row and its status: at a floor when its error is at most kFloorFactor
// times the round-off floor or (numerical reference) the reference's accuracy. A measured floor
// scales to the row's steps N as √(N/N_f) (N_f: the steps of the measurement).
void apply_floor(ConvergenceRow& row, const ConvergenceResult::Floor& fl, bool numerical_ref) {
  row.floor_used = fl.source == "model" ? row.roundoff_floor : fl.value;
  if (fl.source == "perturbed")
    row.floor_used = fl.value * std::sqrt(static_cast<double>(std::max(1L, row.steps)) /
                                          static_cast<double>(std::max(1L, fl.steps)));
  row.floor_source = fl.source;
  row.at_floor = row.stats.status == Status::ok &&
                 (row.error <= kFloorFactor * row.floor_used ||
                  (numerical_ref && row.error <= kFloorFactor * row.reference_floor));
}

// A measured floor estimates the rounding of a level, it does not observe it: a row within
// kFloorFactor of it (but above kFloorKeepFactor times it) whose pairwise order with the coarser
// usable level is within kOrderTolerance of the expected slope still falls at the method's order,
// so rounding does not set its error; it stays ok (and so may the next level, by the same test).
void keep_rows_still_falling(std::vector<ConvergenceRow>& rows, bool local) {
  for (std::size_t k = 1; k < rows.size(); ++k) {
    ConvergenceRow& r = rows[k];
    const ConvergenceRow& prev = rows[k - 1];
    if (!r.at_floor || prev.at_floor || prev.stats.status != Status::ok || !(prev.error > 0) ||
        !(r.error > 0) || r.error <= kFloorKeepFactor * r.floor_used ||
        r.error <= kFloorFactor * r.reference_floor)
      continue;
    const double q = std::log(prev.error / r.error) / std::log(prev.h / r.h);
    if (std::abs(q - (r.order + (local ? 1 : 0))) <= kOrderTolerance) r.at_floor = false;
  }
}

// The rows of one integrator over its ladder, with its round-off floor applied (progress lines
// to st.progress; `done` of `total` rows so far; ref_index: the row's local reference).
void integrator_rows(StudyState& st, Integrator& integ, const std::vector<double>& ladder,
                     std::size_t& ref_index, std::size_t& done, std::size_t total,
                     ConvergenceResult& result) {
  std::ostream* progress = st.progress;
  std::vector<ConvergenceRow> rows;
  std::vector<Vec> finals;
  for (double h : ladder) {
    finals.emplace_back();
    rows.push_back(measure_row(st, integ, h, ref_index++, result, finals.back()));
    if (progress) *progress << progress_line(++done, total, rows.back()) << std::flush;
  }
  ConvergenceResult::Floor fl = integrator_floor(st, integ, rows, finals);
  if (progress && fl.source != "model")
    *progress << "floor: " << fl.integrator << " " << format_short(fl.value) << " (" << fl.source
              << (fl.source == "perturbed" ? ", two reruns at h = " + format_short(fl.h)
                                           : std::string())
              << ")\n";
  if (progress && !fl.note.empty())
    *progress << "floor: " << fl.integrator << " uses the model N·u·s (" << fl.note << ")\n";
  for (auto& row : rows) apply_floor(row, fl, st.numerical_ref);
  if (fl.source == "perturbed") keep_rows_still_falling(rows, st.local);
  for (auto& row : rows) result.rows.push_back(std::move(row));
  result.floors.push_back(std::move(fl));
}

// The order fit of every integrator, with its analysed order and round-off floor.
void add_fits(const Setup& setup, bool local, ConvergenceResult& result) {
  for (std::size_t i = 0; i < setup.integrators.size(); ++i) {
    const Integrator& integ = *setup.integrators[i];
    OrderFit fit = fit_order(result.rows, integ.info().name, local, result.ladder);
    if (const auto a = coefficient_analysis(integ)) fit.analysed_order = a->order;
    fit.floor_used = result.floors[i].value;
    fit.floor_source = result.floors[i].source;
    result.fits.push_back(std::move(fit));
  }
}

ConvergenceResult run_step_study(const ConvergenceSpec& given, std::ostream* progress, bool local) {
  given.validate();
  Setup setup = make_setup(given.model, given.integrators, setup_params(given));
  const OdeSystem& sys = *setup.model;
  ConvergenceSpec spec = given;
  const Resolved h0 = resolve_step(sys, spec.h, spec.model);
  spec.h = h0.value;
  if (progress && h0.source != "--h")
    *progress << "no --h given: starting from the model's suggested step h = "
              << format_full(spec.h) << " (" << h0.source.substr(16) << ")\n";
  StudyState st(spec, sys, local, progress);
  st.t0 = sys.initial_time();
  require_input(spec.t_end > st.t0, "--t-end must be > the model's initial time");
  for (const auto& integ : setup.integrators)
    require_input(
        integ->supports_fixed_step(),
        "integrator '" + integ->info().name +
            "' is adaptive only: a step-size study needs fixed steps (use work-precision)");

  // Actual step sizes are fixed by the driver's N = round(T/h) rule (global study); the local
  // study uses h_k exactly.
  const std::vector<double> hs = spec.step_ladder(spec.h);
  for (double h : hs) fixed_step_count(st.t0, spec.t_end, h, FixedStepOptions{}.max_steps);

  st.plan = plan_reference(spec, sys, hs.back());
  if (!spec.cache_dir.empty() && st.plan.kind != RefKind::exact) require_output_dir(spec.cache_dir);
  st.numerical_ref = st.plan.kind != RefKind::exact;
  st.plan2 = tighter_plan(st.plan);
  ConvergenceResult result;
  result.reference_description = st.plan.description;
  result.h = spec.h;
  result.h_source = h0.source;
  result.ladder = spec.ladder;
  if (st.numerical_ref) result.reference_check_description = st.plan2.description;

  st.given_floor = spec.given_floor();
  result.floor_mode = spec.floor;
  st.y0 = sys.initial_state();
  st.y0_norm = inf_norm(st.y0);
  if (!local) global_reference(st, result);
  st.s_end = std::max({1.0, st.y0_norm, local ? 0.0 : inf_norm(st.ref_end)});

  const std::vector<std::vector<double>> ladders =
      spec.ladder == "per-method" ? per_method_ladders(st, setup, result)
                                  : std::vector<std::vector<double>>(setup.integrators.size(), hs);
  if (local) local_references(st, ladders, result);

  std::size_t total = 0;
  for (const auto& ladder : ladders) total += ladder.size();
  std::size_t done = 0, ref_index = 0;
  for (std::size_t i = 0; i < setup.integrators.size(); ++i)
    integrator_rows(st, *setup.integrators[i], ladders[i], ref_index, done, total, result);
  add_observed_orders(result.rows);
  add_fits(setup, local, result);
  return result;
}

std::string optional_full(const std::optional<double>& x) { return x ? format_full(*x) : ""; }

}  // namespace

ConvergenceResult run_convergence(const ConvergenceSpec& spec, std::ostream* progress) {
  return run_step_study(spec, progress, false);
}

ConvergenceResult run_local_error(const ConvergenceSpec& spec, std::ostream* progress) {
  return run_step_study(spec, progress, true);
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

std::string ConvergenceRow::status_text() const {
  return at_floor ? "floor" : to_string(stats.status);
}

namespace {

// One integrator's rows in ladder order, which of them can enter a fit (ran ok, above the
// floors, positive error) and the pairwise observed order between level b-1 and b.
struct FitLevels {
  std::vector<const ConvergenceRow*> rs;
  std::vector<bool> usable;
  double pair_order(std::size_t b) const {
    return std::log(rs[b - 1]->error / rs[b]->error) / std::log(rs[b - 1]->h / rs[b]->h);
  }
  // The pairwise orders of consecutive usable levels b in [from, to), as "q q q".
  std::string pair_orders(std::size_t from, std::size_t to) const {
    std::string s;
    for (std::size_t b = std::max<std::size_t>(from, 1); b < to; ++b)
      if (usable[b] && usable[b - 1]) s += (s.empty() ? "" : " ") + format_fixed(pair_order(b), 2);
    return s;
  }
};

// The longest run of consecutive usable levels whose pairwise orders agree within
// kOrderAgreement; the finest of equally long runs. {first level, length}.
std::pair<std::size_t, std::size_t> asymptotic_window(const FitLevels& lv) {
  const std::size_t n = lv.rs.size();
  std::size_t best_a = 0, best_len = 0;
  for (std::size_t a = 0; a < n; ++a) {
    if (!lv.usable[a]) continue;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::size_t len = 1;
    for (std::size_t b = a + 1; b < n && lv.usable[b]; ++b) {
      const double q = lv.pair_order(b);
      lo = std::min(lo, q);
      hi = std::max(hi, q);
      if (!(hi - lo <= kOrderAgreement)) break;
      len = b - a + 1;
    }
    if (len >= best_len) {
      best_len = len;
      best_a = a;
    }
  }
  return {best_a, best_len};
}

// Least-squares slope of log error against log h over levels [a, a + len) (len >= 3) and its
// standard error sqrt(SSR / (m - 2) / Sxx).
std::pair<double, double> slope_and_se(const FitLevels& lv, std::size_t a, std::size_t len) {
  std::vector<double> x, y;
  for (std::size_t i = a; i < a + len; ++i) {
    x.push_back(std::log(lv.rs[i]->h));
    y.push_back(std::log(lv.rs[i]->error));
  }
  const double m = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i] / m;
    my += y[i] / m;
  }
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  const double slope = sxy / sxx;
  double ssr = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double res = y[i] - (my + slope * (x[i] - mx));
    ssr += res * res;
  }
  return {slope, std::sqrt(ssr / (m - 2) / sxx)};
}

// The last three pairwise orders up to level `last` (consecutive levels above the floors, two
// when only two exist), finest first.
std::vector<double> last_pair_orders(const FitLevels& lv, std::size_t last) {
  std::vector<double> q;
  for (std::size_t b = last; b >= 1 && q.size() < 3 && lv.usable[b] && lv.usable[b - 1]; --b)
    q.push_back(lv.pair_order(b));
  return q;
}

// Where the last three pairwise orders q1, q2, q3 (coarse to fine; `q` holds them finest first)
// are heading when their steps d1 = q2 - q1, d2 = q3 - q2 have one sign and shrink by a ratio
// r = d2/d1 ≤ 0.75: Aitken's extrapolation q3 + d2 r/(1 - r). Nothing otherwise (nearer r = 1
// the extrapolation is too sensitive to mean anything).
std::optional<double> order_limit(const std::vector<double>& q) {
  if (q.size() < 3) return std::nullopt;
  const double d2 = q[0] - q[1], d1 = q[1] - q[2];
  if (!(d1 * d2 > 0 && std::abs(d2) <= 0.75 * std::abs(d1))) return std::nullopt;
  const double r = d2 / d1;
  return q[0] + d2 * r / (1 - r);
}

// Whether the last pairwise orders q (last_pair_orders) are still moving towards the expected
// slope: they each step towards it, by more than kOrderTolerance in all, and, when the steps
// shrink enough for order_limit, its extrapolated limit is within kOrderReductionSpread of it. A
// pre-asymptotic approach (e.g. backward Euler on a stiff cloth: 0.37 0.62 0.79 0.89, whose limit
// is 1.03) then is not read as a steady reduced order, while orders converging to another value (a
// true reduction) or wandering (noise) are.
bool orders_approach(const std::vector<double>& q, double expected) {
  if (q.size() < 2) return false;
  const double toward = expected - q[0];  // the direction still to go
  const double d2 = q[0] - q[1];
  const double d1 = q.size() == 3 ? q[1] - q[2] : d2;
  if (!(d1 * toward > 0 && d2 * toward > 0)) return false;
  if (std::abs(q.back() - q[0]) <= kOrderTolerance) return false;
  const auto limit = order_limit(q);
  return !limit || std::abs(*limit - expected) <= kOrderReductionSpread;
}

// How a reduced order behaves at the window's fine end, from its last pairwise orders q
// (last_pair_orders, finest first): steady when they agree within kOrderTolerance, else still
// falling or rising (from the coarsest of them to the finest); order_limit then tells where they
// level off.
std::string reduced_trend(const std::vector<double>& q) {
  if (q.size() < 2 ||
      *std::max_element(q.begin(), q.end()) - *std::min_element(q.begin(), q.end()) <=
          kOrderTolerance)
    return "a steady reduced order on this problem";
  return std::string("a reduced order on this problem, still ") +
         (q.front() < q.back() ? "falling" : "rising") + " at the window's fine end (" +
         format_fixed(q.back(), 2) + " to " + format_fixed(q.front(), 2) + ")";
}

// The round-off floor of a row in words: how it was found and its value.
std::string roundoff_words(const ConvergenceRow& r) {
  if (r.floor_source == "perturbed")
    return "the round-off floor (measured by perturbed reruns: " + format_short(r.floor_used) + ")";
  if (r.floor_source == "given")
    return "the round-off floor (--floor " + format_short(r.floor_used) + ")";
  return "the round-off floor (the model N·u·s)";
}

// The finest usable level at or after `from` (`from` itself when none is finer).
std::size_t finest_usable(const FitLevels& lv, std::size_t from) {
  std::size_t last = from;
  for (std::size_t b = from; b < lv.rs.size(); ++b)
    if (lv.usable[b]) last = b;
  return last;
}

// Whether a level finer than `last` (the finest usable one) is at a floor: the floor, not the
// ladder's length, ends the usable levels, so finer steps cannot add usable ones.
bool floor_ends_ladder(const FitLevels& lv, std::size_t last) {
  for (std::size_t b = last + 1; b < lv.rs.size(); ++b)
    if (lv.rs[b]->at_floor) return true;
  return false;
}

// The pairwise orders through the round-off floor rows just finer than `last` (ok rows with a
// positive error, at most two pairs), as "q q" when each is within 0.3 of the expected slope: the
// floor marks levels whose errors still fall at the method's order. Empty otherwise.
std::string orders_through_floor(const FitLevels& lv, std::size_t last, double expected) {
  std::string s;
  int pairs = 0;
  for (std::size_t b = last + 1; b < lv.rs.size() && pairs < 2; ++b) {
    const auto& r = *lv.rs[b];
    const auto& p = *lv.rs[b - 1];
    if (!r.at_floor || r.stats.status != Status::ok || !(r.error > 0) || !(p.error > 0) ||
        p.stats.status != Status::ok)
      break;
    if (r.error > kFloorFactor * r.floor_used) break;  // at the reference's floor, not round-off
    const double q = lv.pair_order(b);
    if (!(std::abs(q - expected) <= 0.3)) return "";
    s += (s.empty() ? "" : " ") + format_fixed(q, 2);
    ++pairs;
  }
  return s;
}

// What changes the result when the floor ends the ladder below its finest usable level `last`: a
// floor that marks levels whose errors still fall at the expected slope is named (the model
// bound: --floor auto measures it; a given one: lower it); otherwise a denser ladder, which keeps
// more levels above the floor over the same range of errors.
std::string floor_end_advice(const FitLevels& lv, std::size_t last, double expected) {
  const auto& r = *lv.rs[std::min(last + 1, lv.rs.size() - 1)];
  const std::string through = orders_through_floor(lv, last, expected);
  if (!through.empty()) {
    const std::string marks = " marks finer levels whose errors still fall at about order " +
                              std::to_string(static_cast<int>(expected)) + " (pairwise orders " +
                              through + ")";
    if (r.floor_source == "given")
      return "--floor " + format_short(r.floor_used) + marks + ": a smaller --floor keeps them";
    if (r.floor_source != "perturbed")
      return "the model N·u·s" + marks + ": --floor auto measures the floor instead of bounding it";
    return "the measured floor" + marks + ": a smaller --refine puts more levels above it";
  }
  return "the floor ends the ladder below them: a smaller --refine puts more levels above it";
}

// What gives more levels where the pairwise orders can settle: finer steps, unless the floor ends
// the ladder (floor_end_advice); a per-method ladder ends about kLadderFloorMargin times above the
// floors by design, whatever --levels says, so only a common ladder goes finer.
std::string finer_levels_advice(const FitLevels& lv, std::size_t last, double expected,
                                const std::string& ladder) {
  if (floor_ends_ladder(lv, last)) return floor_end_advice(lv, last, expected);
  if (ladder == "per-method")
    return "the per-method ladder ends about " + g_short(kLadderFloorMargin) +
           "x above the floors by design: --ladder common with a smaller --h goes down to " +
           g_short(kFloorFactor) + "x";
  return "add --levels or use a smaller --h";
}

// What the pairwise orders of a fit window [a, a + len) and around it show.
struct WindowOrders {
  double q_first = 0, q_last = 0;  // the window's first and last pairwise orders
  double w_lo = 0, w_hi = 0;       // their range over the window
  // A coarser pair near the expected slope (within 0.3): the method showed its order there
  // and something else sets the error in the window.
  bool coarser_near = false;
  std::vector<double> last_orders;  // the pairwise orders up to the window's finest level
  // The finest usable level of the integrator (not only of the window): orders still moving
  // towards the expected slope there make the whole approach pre-asymptotic too.
  std::size_t last_usable = 0;
  bool approaching = false;
  bool near_floors = false;  // that level is within kLadderFloorMargin of its floors
};

WindowOrders window_orders(const FitLevels& lv, std::size_t a, std::size_t len, double expected) {
  WindowOrders w;
  w.q_first = lv.pair_order(a + 1);
  w.q_last = lv.pair_order(a + len - 1);
  w.w_lo = w.w_hi = w.q_first;
  for (std::size_t b = 1; b <= a; ++b)
    if (lv.usable[b] && lv.usable[b - 1] && std::abs(lv.pair_order(b) - expected) <= 0.3)
      w.coarser_near = true;
  for (std::size_t b = a + 1; b < a + len; ++b) {
    w.w_lo = std::min(w.w_lo, lv.pair_order(b));
    w.w_hi = std::max(w.w_hi, lv.pair_order(b));
  }
  w.last_orders = last_pair_orders(lv, a + len - 1);
  w.last_usable = finest_usable(lv, a + len - 1);
  w.approaching = orders_approach(w.last_orders, expected) ||
                  orders_approach(last_pair_orders(lv, w.last_usable), expected);
  const auto& finest = *lv.rs[w.last_usable];
  w.near_floors =
      finest.error <= kLadderFloorMargin * std::max(finest.floor_used, finest.reference_floor);
  return w;
}

// Why a fit over the window [a, a + len) is more than kOrderTolerance from the expected slope,
// read from the pairwise orders. A steady window (orders within 0.1): the method's order on this
// problem. The window's orders moving towards the expected slope: pre-asymptotic.
std::string off_fit_reason(const FitLevels& lv, std::size_t a, std::size_t len, double slope,
                           int expected_slope, const std::string& ladder) {
  const double expected = expected_slope;
  const std::string all = lv.pair_orders(1, lv.rs.size());
  const WindowOrders w = window_orders(lv, a, len, expected);
  const auto& [q_first, q_last, w_lo, w_hi, coarser_near, last_orders, last_usable, approaching,
               near_floors] = w;
  const auto limit = order_limit(last_orders);
  const std::string levelling =
      limit ? " (levelling off near " + format_fixed(*limit, 2) + ")" : std::string();
  std::string reason;
  // Pairwise orders still moving towards the classical order at the window's finest level
  // (orders_approach): pre-asymptotic, whatever the window's slope; not an order reduction.
  if (approaching)
    reason = "pre-asymptotic: the pairwise orders are still moving towards " +
             std::to_string(expected_slope) + " at the finest level above the floors (" + all +
             "), so " + format_fixed(slope, 2) + " is not the method's order on this problem: " +
             finer_levels_advice(lv, last_usable, expected, ladder);
  // Below the classical order by more than kOrderReductionSpread over a window whose pairwise
  // orders agree (within kOrderAgreement, as every fit window): the method's reduced order on
  // this problem.
  else if (slope < expected - kOrderReductionSpread && !coarser_near)
    reason = "order reduction to " + format_fixed(slope, 2) + " (classical " +
             std::to_string(expected_slope) + "): " + reduced_trend(last_orders) +
             ", as on stiff problems where the stage order or the lack of stiff accuracy sets "
             "it; pairwise orders " +
             all + levelling;
  else if (coarser_near)
    reason = "the error stops following h^" + std::to_string(expected_slope) +
             " below h = " + format_short(lv.rs[a]->h) +
             ": something other than the truncation error sets it there (a solver "
             "tolerance, order reduction or the reference); pairwise orders " +
             all;
  // Above the classical order by more than half an order down to the finest pair: more accurate
  // than the order promises (an error term vanishes on this problem), not a pre-asymptotic
  // approach from above (whose finest pairs come within half an order).
  else if (slope > expected + kOrderReductionSpread && q_last > expected + 0.5)
    reason = "a higher order than the classical " + std::to_string(expected_slope) + ": " +
             format_fixed(slope, 2) +
             " on this problem (a leading error term vanishes on it, e.g. a splitting whose "
             "parts commute on the solution's manifold, or a superconvergent point); pairwise "
             "orders " +
             all;
  // Above the classical order by less than half an order where the floors end the ladder: the
  // next error term still weighs there; the asymptotic order is not reached above the floors.
  else if (slope > expected && near_floors)
    reason = format_fixed(slope - expected, 2) + " above " + std::to_string(expected_slope) +
             " where the floors end the ladder (pairwise orders " + all +
             "): the next error term still weighs at these steps, so the asymptotic order is not "
             "reached above the floors";
  else if (w_hi - w_lo <= kOrderTolerance)
    reason = "a steady order of " + format_fixed(slope, 2) + ", not " +
             std::to_string(expected_slope) +
             ", on this problem (e.g. order reduction to the stage order on a stiff "
             "problem, or structure that changes the order); pairwise orders " +
             all;
  else if (std::abs(q_last - expected) < std::abs(q_first - expected))
    reason = "pre-asymptotic: the pairwise orders approach " + std::to_string(expected_slope) +
             " only slowly (" + all + ") down to the finest level above the floors";
  else
    reason = "fitted order differs from the classical one by " + format_fixed(slope - expected, 2) +
             "; pairwise orders " + all;
  // The finest usable level of the integrator (not only of the window) near the floors.
  if (!approaching && near_floors && !(slope > expected))
    reason += "; the floors (within " + g_short(kLadderFloorMargin) +
              "x of the finest level above them) stop the ladder before the orders settle";
  return reason;
}

// The fit over the window of `best_len` >= 3 consecutive agreeing levels from `best_a`, and the
// reason when it is off the expected slope or finer levels do not follow it.
void fit_over_window(const FitLevels& lv, std::size_t best_a, std::size_t best_len,
                     const std::string& ladder, OrderFit& fit) {
  const std::size_t n = lv.rs.size();
  const auto [slope, se] = slope_and_se(lv, best_a, best_len);
  fit.fitted = slope;
  fit.fitted_se = se;
  fit.h_max = lv.rs[best_a]->h;
  fit.h_min = lv.rs[best_a + best_len - 1]->h;
  fit.levels_used = static_cast<int>(best_len);
  // Levels finer than the window, above the floors, that do not agree with it: named even when
  // the fit is close to the expected slope (e.g. a solver tolerance that sets the error at fine
  // h must not disappear behind a clean fit over the coarse levels).
  const std::string finer = lv.pair_orders(best_a + best_len, n);
  if (!finer.empty())
    fit.reason = "levels finer than the window (h < " + format_short(fit.h_min) +
                 ") are above the floors but do not follow it (pairwise orders " + finer +
                 "): a solver tolerance, order reduction or the reference sets their error, "
                 "or they are still pre-asymptotic";
  if (std::abs(slope - fit.expected_slope) > kOrderTolerance) {
    // The finest pair above the floors within kOrderTolerance of the classical order, beyond
    // a window that is not: the window is the pre-asymptotic range (e.g. symplectic Euler on
    // the cloth: 2.16 2.04 2.01 2.00 1.99, then 1.00 where the first-order term takes over in
    // the max-norm), and the asymptotic order is the classical one. Otherwise the window's
    // reason, followed by the finer levels' note.
    double q_finest = std::numeric_limits<double>::quiet_NaN();
    std::size_t b_finest = 0;
    for (std::size_t b = best_a + best_len; b < n; ++b)
      if (lv.usable[b] && lv.usable[b - 1]) {
        q_finest = lv.pair_order(b);
        b_finest = b;
      }
    if (!finer.empty() && std::abs(q_finest - fit.expected_slope) <= kOrderTolerance)
      fit.reason = "pre-asymptotic window: the finest pair above the floors (h = " +
                   format_short(lv.rs[b_finest - 1]->h) + " to " +
                   format_short(lv.rs[b_finest]->h) + ") gives " + format_fixed(q_finest, 2) +
                   ", the classical order, after " + format_fixed(slope, 2) +
                   " over the window (pairwise orders " + lv.pair_orders(1, n) + "): " +
                   (floor_ends_ladder(lv, b_finest)
                        ? floor_end_advice(lv, b_finest, fit.expected_slope)
                        : "add levels below h = " + format_short(lv.rs[b_finest]->h) +
                              " to fit the asymptotic range");
    else
      fit.reason = off_fit_reason(lv, best_a, best_len, slope, fit.expected_slope, ladder) +
                   (finer.empty() ? "" : "; " + fit.reason);
  }
}

// No three consecutive usable levels agree: still approaching the order (pre-asymptotic) or
// wandering (unsettled); finer levels help unless the floor ends the ladder.
std::string unsettled_reason(const FitLevels& lv, int expected_slope, const std::string& ladder) {
  const std::size_t n = lv.rs.size();
  const double expected = expected_slope;
  std::size_t last = 0;
  for (std::size_t b = 0; b < n; ++b)
    if (lv.usable[b]) last = b;
  const std::string all = lv.pair_orders(1, n);
  const std::string agree = "no three consecutive levels agree within " + g_short(kOrderAgreement);
  if (orders_approach(last_pair_orders(lv, last), expected))
    return "pre-asymptotic: the pairwise orders above the floors are still moving "
           "towards " +
           std::to_string(expected_slope) + " (" + all + "; " + agree +
           "): " + finer_levels_advice(lv, last, expected, ladder);
  return "unsettled orders: the pairwise orders above the floors (" + all + ") " +
         "neither settle (" + agree + ") nor approach " + std::to_string(expected_slope) +
         " (noise, a solver tolerance or a change of regime at these steps): " +
         (floor_ends_ladder(lv, last) ? floor_end_advice(lv, last, expected)
                                      : "add --levels to see whether they settle at finer steps");
}

// After "only K levels above ": the round-off floor, how many rows are at it and what to change.
// The finest usable level (or the coarsest level when none is usable) and the first round-off floor
// row after it, whose floor the reason names.
std::string roundoff_reason(const FitLevels& lv, int n_usable, int n_roundoff, double expected,
                            const std::string& ladder) {
  std::size_t last = 0;
  for (std::size_t b = 0; b < lv.rs.size(); ++b)
    if (lv.usable[b]) last = b;
  const ConvergenceRow* floor_row = nullptr;
  for (const auto* r : lv.rs)
    if (r->at_floor && r->error <= kFloorFactor * r->floor_used && !floor_row) floor_row = r;
  const std::string through = n_usable > 0 ? orders_through_floor(lv, last, expected) : "";
  std::string advice;
  if (!through.empty() && floor_row->floor_source != "perturbed")
    advice = floor_end_advice(lv, last, expected);
  else if (ladder == "per-method")
    advice =
        "use a larger --h (the probe's steps stay within [h/64, 16·h]) or a smaller "
        "--refine (the same levels over a shorter range of steps)";
  else
    advice = "use a larger --h or --ladder per-method";
  return roundoff_words(*floor_row) + ", " + std::to_string(n_roundoff) + " at it: " + advice;
}

}  // namespace

OrderFit fit_order(const std::vector<ConvergenceRow>& rows, const std::string& integrator,
                   bool local, const std::string& ladder) {
  OrderFit fit;
  fit.integrator = integrator;
  FitLevels lv;
  for (const auto& r : rows)
    if (r.integrator == integrator) lv.rs.push_back(&r);
  if (lv.rs.empty()) {
    fit.reason = "no rows";
    return fit;
  }
  fit.order = lv.rs.front()->order;
  fit.expected_slope = fit.order + (local ? 1 : 0);
  const std::size_t n = lv.rs.size();
  lv.usable.assign(n, false);
  int n_usable = 0, n_roundoff = 0, n_reference = 0, n_failed = 0;
  std::string failed_status;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& r = *lv.rs[i];
    lv.usable[i] = r.stats.status == Status::ok && !r.at_floor && std::isfinite(r.error) &&
                   r.error > 0 && r.h > 0;
    n_usable += lv.usable[i] ? 1 : 0;
    if (r.stats.status != Status::ok) {
      ++n_failed;
      failed_status = to_string(r.stats.status);
    } else if (r.at_floor) {
      ++(r.error <= kFloorFactor * r.floor_used ? n_roundoff : n_reference);
    }
  }
  const auto [best_a, best_len] = asymptotic_window(lv);
  if (best_len >= 3) {
    fit_over_window(lv, best_a, best_len, ladder, fit);
    return fit;
  }
  const std::string k = std::to_string(n_usable);
  const std::string levels = n_usable == 1 ? " level" : " levels";
  const double expected = fit.expected_slope;
  if (n_usable >= 3) {
    fit.reason = unsettled_reason(lv, fit.expected_slope, ladder);
  } else if (n_roundoff > 0) {
    fit.reason = "only " + k + levels + " above " +
                 roundoff_reason(lv, n_usable, n_roundoff, expected, ladder);
  } else if (n_reference > 0) {
    fit.reason = "only " + k + levels +
                 " above the reference's accuracy: tighten --reference-rtol or use a more "
                 "accurate --reference";
  } else if (n_failed > 0) {
    fit.reason = "only " + k + levels + " ran ok (the others ended " + failed_status +
                 "): use a smaller --h";
  } else {
    fit.reason = "only " + k + levels + " with a positive error: add --levels";
  }
  return fit;
}

namespace {

// The columns every row of both tables ends with, after the existing ones.
void add_trailing_columns(Table& t) {
  for (const auto& c : SolveStats::counter_names()) t.columns.push_back(c);
  t.columns.push_back("roundoff_floor");
  t.columns.push_back("reference_floor");
  t.columns.push_back("floor_used");
  t.columns.push_back("floor_source");
}

void add_trailing_values(std::vector<std::string>& row, const ConvergenceRow& r) {
  for (const auto& v : r.stats.counter_values()) row.push_back(v);
  row.push_back(format_full(r.roundoff_floor));
  row.push_back(format_full(r.reference_floor));
  row.push_back(format_full(r.floor_used));
  row.push_back(r.floor_source);
}

}  // namespace

Table convergence_table(const ConvergenceResult& res) {
  Table t{{"model", "integrator", "order", "h", "steps", "error", "observed_order", "f_evals",
           "jac_evals", "lin_solves", "wall_s", "status"},
          {}};
  add_trailing_columns(t);
  for (const auto& r : res.rows) {
    std::vector<std::string> row = {r.model,
                                    r.integrator,
                                    std::to_string(r.order),
                                    format_full(r.h),
                                    std::to_string(r.steps),
                                    r.stats.status == Status::ok ? format_full(r.error) : "",
                                    optional_full(r.observed_order),
                                    std::to_string(r.stats.f_evals),
                                    std::to_string(r.stats.jac_evals),
                                    SolveStats::count_text(r.stats.lin_solves),
                                    format_full(r.stats.wall_s),
                                    r.status_text()};
    add_trailing_values(row, r);
    t.rows.push_back(std::move(row));
  }
  return t;
}

Table local_error_table(const ConvergenceResult& res) {
  Table t{{"model", "integrator", "order", "h", "local_error", "observed_order", "status",
           "f_evals", "jac_evals", "lin_solves"},
          {}};
  add_trailing_columns(t);
  for (const auto& r : res.rows) {
    std::vector<std::string> row = {r.model,
                                    r.integrator,
                                    std::to_string(r.order),
                                    format_full(r.h),
                                    r.stats.status == Status::ok ? format_full(r.error) : "",
                                    optional_full(r.observed_order),
                                    r.status_text(),
                                    std::to_string(r.stats.f_evals),
                                    std::to_string(r.stats.jac_evals),
                                    SolveStats::count_text(r.stats.lin_solves)};
    add_trailing_values(row, r);
    t.rows.push_back(std::move(row));
  }
  return t;
}

Table orders_table(const ConvergenceResult& res) {
  Table t{{"integrator", "order", "analysed_order", "fitted_order", "fitted_order_se", "h_min",
           "h_max", "levels_used", "reason", "floor_used", "floor_source"},
          {}};
  for (const auto& f : res.fits)
    t.rows.push_back({f.integrator, std::to_string(f.order),
                      f.analysed_order ? std::to_string(*f.analysed_order) : "",
                      optional_full(f.fitted), optional_full(f.fitted_se),
                      f.fitted ? format_full(f.h_min) : "", f.fitted ? format_full(f.h_max) : "",
                      std::to_string(f.levels_used), f.reason, format_full(f.floor_used),
                      f.floor_source});
  return t;
}

namespace {

// The summary of the fits: the fitted order with its window; the verdict uses the fitted order.
Table fits_markdown_table(const ConvergenceResult& res, bool local) {
  Table t{{"integrator", local ? "expected slope (order+1)" : "order", "fitted", "± SE", "window h",
           "levels", "within 0.1", "reason"},
          {}};
  for (const auto& f : res.fits) {
    const bool fitted = f.fitted.has_value();
    t.rows.push_back(
        {f.integrator, std::to_string(f.expected_slope), fitted ? format_fixed(*f.fitted) : "-",
         fitted ? format_fixed(*f.fitted_se) : "",
         fitted ? format_short(f.h_min) + " – " + format_short(f.h_max) : "",
         std::to_string(f.levels_used),
         fitted ? (std::abs(*f.fitted - f.expected_slope) <= kOrderTolerance ? "yes" : "no") : "-",
         f.reason});
  }
  return t;
}

// The floors, in words, for the Markdown and the report.
std::string floors_sentence(const ConvergenceResult& res, bool local) {
  std::ostringstream os;
  const std::string model =
      std::string(local ? "u·s" : "N·u·s") + ", u = 2^-53, s = max(1, ‖y0‖∞, ‖y_ref‖∞)";
  os << "Rows with status `floor` have an error within " << g_short(kFloorFactor)
     << "× the round-off floor (";
  if (res.floor_mode == "auto") {
    int measured = 0;
    for (const auto& f : res.floors) measured += f.source == "perturbed" ? 1 : 0;
    os << "measured per method from two reruns at its finest step from y0 scaled by 1 ± 2^-30 "
          "per component: twice the max-norm of (y₊ + y₋)/2 − y, the part of the result that "
          "is rounding"
       << (local ? "" : ", times √(N/N_f) at a level of N steps") << "; the `floor_used` column";
    if (measured < static_cast<int>(res.floors.size()))
      os << "; the model " << model << " for " << res.floors.size() - measured
         << " method(s) with nothing to measure";
    os << "; a row above a measured floor whose pairwise order is within "
       << g_short(kOrderTolerance) << " of the expected slope stays ok";
  } else if (res.floor_mode == "model") {
    os << "the model " << model << ", from --floor model";
  } else {
    os << "--floor " << res.floor_mode;
  }
  os << ")";
  if (res.reference_accuracy)
    os << " or the reference's accuracy (≈ " << format_short(*res.reference_accuracy)
       << (local ? " at worst" : "") << ", from a second run: " << res.reference_check_description
       << ")";
  os << "; fits leave them out. The fitted order is the least-squares slope over the longest run "
        "of consecutive levels above the floors whose pairwise orders agree within "
     << g_short(kOrderAgreement) << ".";
  if (res.ladder == "per-method")
    os << " Per-method ladders: each method's steps come from a probe (coarsest error at most "
          "about "
       << g_short(kLadderTop) << "·s, finest about " << g_short(kLadderFloorMargin)
       << "× the floors where the ladder's length allows).";
  return os.str();
}

}  // namespace

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
  os << floors_sentence(res, local) << "\n\n";
  os << fits_markdown_table(res, local).to_markdown() << "\n";
  Table detail = local ? local_error_table(res) : convergence_table(res);
  // Shorter numbers in the Markdown copy; the CSV keeps full precision.
  for (auto& row : detail.rows)
    for (std::size_t c = 0; c < detail.columns.size(); ++c) {
      const auto& col = detail.columns[c];
      if ((col == "h" || col == "error" || col == "local_error" || col == "wall_s" ||
           col == "roundoff_floor" || col == "reference_floor" || col == "floor_used") &&
          !row[c].empty())
        row[c] = format_short(std::stod(row[c]), col == "wall_s" ? 2 : 3);
      if (col == "observed_order" && !row[c].empty()) row[c] = format_fixed(std::stod(row[c]));
    }
  os << detail.to_markdown();
  std::vector<RunNote> notes;
  for (const auto& r : res.rows)
    notes.push_back({r.integrator + ", h = " + format_short(r.h), &r.stats});
  os << failed_runs_markdown(notes);
  os << "\nFull-precision values: `" << name << ".csv`; order fits: `" << name
     << "_orders.csv`; metadata: `" << name << ".json`.\n";
  return os.str();
}

}  // namespace

void write_convergence_outputs(const std::string& dir, const std::string& name,
                               const ConvergenceSpec& spec, const ConvergenceResult& res,
                               bool local) {
  const std::filesystem::path d(dir);
  const Table t = local ? local_error_table(res) : convergence_table(res);
  write_file_atomic(d / (name + ".csv"), t.to_csv());
  write_file_atomic(d / (name + "_orders.csv"), orders_table(res).to_csv());
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
  meta["floor_factor"] = kFloorFactor;
  meta["unit_roundoff"] = kUnitRoundoff;
  meta["roundoff_floor"] =
      local ? "u*s, s = max(1, |y0|inf, |y_ref|inf)" : "N*u*s, s = max(1, |y0|inf, |y_ref|inf)";
  meta["floor"] = res.floor_mode;
  meta["floor_perturbation"] = kFloorPerturbation;
  meta["floor_seed"] = kFloorSeed;
  nlohmann::json floors = nlohmann::json::array();
  for (const auto& f : res.floors) {
    nlohmann::json j = {{"integrator", f.integrator}, {"floor", f.value}, {"source", f.source}};
    if (f.source == "perturbed" || !f.spreads.empty()) {
      j["h"] = f.h;
      j["steps"] = f.steps;
      nlohmann::json sp = nlohmann::json::array();
      for (double x : f.spreads) sp.push_back(std::isfinite(x) ? nlohmann::json(x) : nullptr);
      j["spreads"] = sp;
    }
    if (!f.note.empty()) j["note"] = f.note;
    floors.push_back(j);
  }
  meta["floors"] = floors;
  meta["order_agreement"] = kOrderAgreement;
  if (res.reference_accuracy) {
    meta["reference_check"] = res.reference_check_description;
    meta["reference_accuracy"] = *res.reference_accuracy;
    if (!res.reference_check_cache.empty())
      meta["reference_check_cache"] = res.reference_check_cache;
  }
  if (!res.reference_accuracy && !res.reference_check_description.empty())
    meta["reference_check"] = res.reference_check_description;
  meta["ladder"] = res.ladder;
  if (!res.ladders.empty()) {
    nlohmann::json lad = nlohmann::json::array();
    for (const auto& l : res.ladders) {
      nlohmann::json probes = nlohmann::json::array();
      for (const auto& [h, e] : l.probes)
        probes.push_back({{"h", h}, {"error", std::isfinite(e) ? nlohmann::json(e) : nullptr}});
      nlohmann::json entry = {{"integrator", l.integrator}, {"h0", l.h0}, {"probes", probes}};
      if (l.floor_h > 0) entry["probe_floor"] = {{"h", l.floor_h}, {"floor", l.floor}};
      lad.push_back(entry);
    }
    meta["ladders"] = lad;
  }
  write_file_atomic(d / (name + ".json"), meta.dump(2) + "\n");
}

Vec adaptive_state_at_end(const OdeSystem& sys, const Params& params, const std::string& method,
                          std::optional<double> rtol, std::optional<double> atol, double t_end,
                          std::string* description) {
  StepStudySpec spec;
  spec.params = params;
  spec.reference = method;
  spec.reference_rtol = rtol;
  spec.reference_atol = atol;
  return reference_at_end(spec, sys, t_end, t_end, description);
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

ReferenceChoice choose_reference(const StepStudySpec& spec, const OdeSystem* sys, double t_end,
                                 double h_fine) {
  ReferenceChoice c;
  const std::string& given = spec.reference;
  c.kind = given == "auto" || given == "exact" || given == "published" ? given : "method";
  c.method = c.kind == "method" ? given : "cvode_bdf";
  if (c.kind == "method") {
    // A method file is compared by the name it registers (the same file, or one with the same
    // text, registers one name).
    const auto name_of = [](const std::string& token) {
      return is_method_file_token(token) ? resolve_integrator_tokens({token}).front() : token;
    };
    c.method = name_of(given);
    try {
      integrator_registry().at(c.method);  // an unknown method, with the closest names
    } catch (const BadInput& e) {
      throw BadInput("--reference: " + std::string(e.what()));
    }
    std::vector<std::string> studied;
    for (const auto& integ : spec.integrators) studied.push_back(name_of(integ));
    if (std::find(studied.begin(), studied.end(), c.method) != studied.end()) {
      std::string other;  // a reference to suggest: a stiff library code not studied here
      for (const char* m : {"cvode_bdf", "radau5", "rodas4"})
        if (other.empty() && std::find(studied.begin(), studied.end(), m) == studied.end())
          other = m;
      throw BadInput("--reference " + given +
                     " is also one of --integrators: a method measured against itself shares its "
                     "own errors, so its points would show their correlation, not its accuracy; "
                     "pass a method that is not studied as --reference" +
                     (other.empty() ? "" : " (e.g. " + other + ")") +
                     ", or --reference published / exact where the model has that solution");
    }
  }
  if (sys) {
    require_input(c.kind != "exact" || sys->has_exact(),
                  "--reference exact: model '" + spec.model +
                      "' has no exact solution (pass --reference published where it has a "
                      "published one, or --reference METHOD, e.g. cvode_bdf)");
    if (c.kind == "auto" && sys->has_exact()) c.kind = "exact";
    const auto pub = sys->published_solution();
    const bool has = pub && std::abs(t_end - pub->t) <= 1e-12 * std::abs(pub->t);
    require_input(c.kind != "published" || has,
                  "--reference published: model '" + spec.model + "' has no published solution" +
                      (pub ? " at t_end = " + format_full(t_end) +
                                 " (its published solution is at t = " + format_full(pub->t) +
                                 ": pass --t-end " + format_full(pub->t) + ")"
                           : std::string(" (pass --reference METHOD, e.g. cvode_bdf)")));
  }
  c.numerical = spec;
  c.numerical.reference = c.kind == "exact" ? "exact" : c.method;
  c.check = c.numerical;
  if (c.check.reference_rtol) *c.check.reference_rtol /= kReferenceTightening;
  if (c.check.reference_atol) *c.check.reference_atol /= kReferenceTightening;
  if (sys && c.kind != "exact" &&
      !integrator_registry().create(c.method, spec.params)->supports_adaptive()) {
    // reference_at_end runs a fixed-step method at h_fine/16: half the step.
    c.check_h_factor = 0.5;
    c.check_description = c.method + " with h = (finest h)/32 = " + format_full(h_fine / 32);
  }
  return c;
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
    md << note << " Reference: " << result_.reference_description << ". "
       << floors_sentence(result_, local_) << "\n\n";
    md << fits_markdown_table(result_, local_).to_markdown() << "\n";
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
  k.options.push_back(
      {"ladder",
       ParamType::text,
       "common",
       "common: every integrator on h/refine^k; per-method: each integrator's coarsest step "
       "found by a short probe so its errors run from about 1e-2 of the solution's size down to "
       "well above its floor",
       {"common", "per-method"}});
  k.options.push_back(
      {"floor", ParamType::text, "auto",
       "the round-off floor a row must stay 10x above to enter the order fit: auto (measured per "
       "method from two reruns at its finest step with y0 scaled by 1 +- 2^-30), model (N*u*s, "
       "an upper bound) or an absolute error VALUE"});
  k.extra_files = {std::string(local ? "local_error" : "convergence") + "_orders.csv"};
  for (auto& o : k.options) {
    if (o.key == "reference_rtol") o.help += " (default 1e-12)";
    if (o.key == "reference_atol") o.help += " (default rtol/100)";
  }
  if (!local) k.required = {"t_end"};
  k.unit_columns =
      (local ? local_error_table(ConvergenceResult{}) : convergence_table(ConvergenceResult{}))
          .columns;
  k.make = [local](const StudyInputs& t, const Params& o, const StudyContext& ctx) {
    ConvergenceSpec spec;
    spec.model = t.model;
    spec.params = t.params;
    spec.integrators = t.integrators;
    read_step_study_options(o, spec);
    spec.ladder = o.text("ladder");
    spec.floor = o.text("floor");
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

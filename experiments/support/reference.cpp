#include "experiments/support/reference.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/output/output.hpp"
#include "experiments/support/step_study.hpp"

namespace stiffbench {

namespace {

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

// An integrator by label: the request's inputs (the studied ones, a user's objects, then the
// process-wide registry); without inputs (a spec checked by its names alone) the registry.
const IntegratorRegistry::Entry* find_method(const ReferenceRequest& req, const std::string& name) {
  return req.inputs ? req.inputs->find_integrator(name) : integrator_registry().find(name);
}

const IntegratorRegistry::Entry& method_entry(const ReferenceRequest& req,
                                              const std::string& name) {
  return req.inputs ? req.inputs->integrator_entry(name) : integrator_registry().at(name);
}

std::unique_ptr<Integrator> create_method(const ReferenceRequest& req, const std::string& name,
                                          const Params& params) {
  return req.inputs ? req.inputs->create_integrator(name, params)
                    : integrator_registry().create(name, params);
}

const std::vector<ParamSpec>& model_param_specs(const ReferenceRequest& req) {
  return req.inputs ? req.inputs->model_entry().params : model_registry().at(req.model).params;
}

}  // namespace

ReferencePlan plan_reference(const ReferenceRequest& req, const OdeSystem& sys, double h_finest) {
  ReferencePlan plan;
  const bool tol_given = req.rtol.has_value() || req.atol.has_value();
  const std::string tol_flag = req.rtol ? kStepFlags.reference_rtol : kStepFlags.reference_atol;
  if (req.method == "exact" || (req.method == "auto" && sys.has_exact())) {
    require_input(sys.has_exact(), std::string(kStepFlags.reference) + " exact: model '" +
                                       sys.name() +
                                       "' has no exact solution (pass --reference METHOD, e.g. " +
                                       std::string(kStepFlags.reference) + " cvode_bdf)");
    require_input(!tol_given, tol_flag +
                                  " applies to an adaptive --reference only: this study uses "
                                  "the exact solution of model '" +
                                  sys.name() +
                                  "' (omit it, or pass --reference cvode_bdf to compare against "
                                  "an adaptive run)");
    plan.description = "exact";
    return plan;
  }
  if (req.method == "auto") {
    throw BadInput("model '" + sys.name() +
                   "' has no exact solution: pass --reference METHOD (an adaptive integrator "
                   "such as cvode_bdf, run at --reference-rtol, default " +
                   format_full(kStepReferenceRtol) +
                   "; or a fixed-step one such as rk4, run at (finest h)/16)");
  }
  const auto* entry = find_method(req, req.method);
  require_input(entry != nullptr, std::string(kStepFlags.reference) + " '" + req.method +
                                      "': neither 'exact' nor an integrator; known: " +
                                      join(integrator_registry().names()));
  plan.method = req.method;
  const std::string owner = "integrator '" + plan.method + "'";
  auto probe = create_method(req, plan.method, req.params);
  require_input(probe->supports_adaptive() || probe->supports_fixed_step(),
                std::string(kStepFlags.reference) + " '" + plan.method +
                    "' has neither a fixed-step nor an adaptive mode");
  try {
    check_compatible(probe->info(), sys);
  } catch (const BadInput& e) {
    throw BadInput(std::string(kStepFlags.reference) + ": " + std::string(e.what()));
  }
  if (probe->supports_adaptive()) {
    const double rtol = req.rtol.value_or(kStepReferenceRtol);
    const double atol = req.atol.value_or(rtol / kStepReferenceAtolDivisor);
    if (!declares(entry->params, "rtol") || !declares(entry->params, "atol"))
      throw std::logic_error(owner + " is adaptive but declares no rtol/atol parameters");
    Params user = req.params;
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
    plan.params = resolve_params(entry->params, req.params, nullptr, owner);
    plan.description = plan.method + " with h = (finest h)/16 = " + format_full(plan.h);
  }
  return plan;
}

// y_ref at `times` (increasing, after t0), from the model's initial state.
std::vector<Vec> compute_reference(const ReferenceRequest& req, const ReferencePlan& plan,
                                   const OdeSystem& sys, const std::vector<double>& times) {
  std::vector<Vec> out;
  if (plan.kind == RefKind::exact) {
    for (double t : times) {
      Vec y(sys.dimension());
      sys.exact(t, y);
      out.push_back(y);
    }
    return out;
  }
  auto integ = create_method(req, plan.method, plan.params);
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

namespace {

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

std::string cache_key(const ReferenceRequest& req, const OdeSystem& sys, const ReferencePlan& plan,
                      const std::vector<double>& times) {
  const Params model_params =
      resolve_params(model_param_specs(req), req.params, nullptr, "model '" + req.model + "'");
  std::uint64_t y0_hash = kFnvOffset;
  const Vec y0 = sys.initial_state();
  for (Index i = 0; i < y0.size(); ++i) y0_hash = fnv1a64(g17(y0[i]) + ",", y0_hash);
  nlohmann::json key;
  key["cache_format"] = 3;  // 2: with the system's fingerprint; 3: with its content's hash
  key["stiffbench_version"] = STIFFBENCH_VERSION;
  key["git_revision"] = git_revision();
  key["model"] = req.model;
  key["model_params"] = model_params.values();
  key["dimension"] = static_cast<long>(sys.dimension());
  key["initial_state_fnv1a"] = hex16(y0_hash);
  key["system_fingerprint"] = system_fingerprint(sys);
  key[kReferenceKey] = plan.method;
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

}  // namespace

ReferenceValues reference_values(const ReferenceRequest& req, const OdeSystem& sys,
                                 const ReferencePlan& plan, std::vector<double> times,
                                 std::ostream* progress) {
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  ReferenceValues res;
  std::vector<Vec> values;
  const bool use_cache = plan.kind != RefKind::exact && !req.cache_dir.empty();
  std::filesystem::path path;
  std::string key_line;
  if (use_cache) {
    key_line = "# key: " + cache_key(req, sys, plan, sorted);
    path =
        std::filesystem::path(req.cache_dir) / "reference/" / (hex16(fnv1a64(key_line)) + ".csv");
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
    values = compute_reference(req, plan, sys, sorted);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (use_cache) {
      std::ostringstream readable;
      readable << "model " << req.model;
      for (const auto& [k, v] : req.params.values()) readable << " " << k << "=" << v;
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

Vec reference_at_end(const ReferenceRequest& req, const OdeSystem& sys, double t_end, double h_fine,
                     std::string* description) {
  Vec y(sys.dimension());
  const bool exact = req.method == "exact" || (req.method == "auto" && sys.has_exact());
  if (exact) {
    require_input(sys.has_exact(), std::string(kStepFlags.reference) + " exact: model '" +
                                       sys.name() + "' has no exact solution");
    sys.exact(t_end, y);
    *description = "exact";
    return y;
  }
  const std::string method = req.method == "auto" ? "cvode_bdf" : req.method;
  Params p = req.params;
  const auto& entry = method_entry(req, method);
  if (declares(entry.params, "rtol")) {
    p.set("rtol", format_full(req.rtol.value_or(1e-14)));
    p.set("atol", format_full(req.atol.value_or(1e-16)));
  }
  auto integ = create_method(req, method, p);
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

ReferenceChoice choose_reference(const ReferenceRequest& req,
                                 const std::vector<std::string>& studied_tokens,
                                 const OdeSystem* sys, double t_end, double h_fine) {
  ReferenceChoice c;
  const std::string& given = req.method;
  c.kind = given == "auto" || given == "exact" || given == "published" ? given : "method";
  c.method = c.kind == "method" ? given : "cvode_bdf";
  if (c.kind == "method") {
    // A method file is compared by the name it registers (the same file, or one with the same
    // text, registers one name). Options read from the command line or a spec file hold labels
    // already; a program may still fill the spec with a path.
    const auto name_of = [](const std::string& token) {
      return is_method_file_token(token) ? resolve_integrator_tokens({token}).front() : token;
    };
    c.method = name_of(given);
    try {
      method_entry(req, c.method);  // an unknown method, with the closest names
    } catch (const BadInput& e) {
      throw BadInput(std::string(kStepFlags.reference) + ": " + std::string(e.what()));
    }
    std::vector<std::string> studied;
    for (const auto& integ : studied_tokens) studied.push_back(name_of(integ));
    if (std::find(studied.begin(), studied.end(), c.method) != studied.end()) {
      std::string other;  // a reference to suggest: a stiff library code not studied here
      for (const char* m : {"cvode_bdf", "radau5", "rodas4"})
        if (other.empty() && std::find(studied.begin(), studied.end(), m) == studied.end())
          other = m;
      throw BadInput(std::string(kStepFlags.reference) + " " + given +
                     " is also one of --integrators: a method measured against itself shares its "
                     "own errors, so its points would show their correlation, not its accuracy; "
                     "pass a method that is not studied as --reference" +
                     (other.empty() ? "" : " (e.g. " + other + ")") +
                     ", or --reference published / exact where the model has that solution");
    }
  }
  if (sys) {
    require_input(c.kind != "exact" || sys->has_exact(),
                  std::string(kStepFlags.reference) + " exact: model '" + req.model +
                      "' has no exact solution (pass --reference published where it has a "
                      "published one, or --reference METHOD, e.g. cvode_bdf)");
    if (c.kind == "auto" && sys->has_exact()) c.kind = "exact";
    const auto pub = sys->published_solution();
    const bool has = pub && std::abs(t_end - pub->t) <= 1e-12 * std::abs(pub->t);
    require_input(c.kind != "published" || has,
                  std::string(kStepFlags.reference) + " published: model '" + req.model +
                      "' has no published solution" +
                      (pub ? " at t_end = " + format_full(t_end) +
                                 " (its published solution is at t = " + format_full(pub->t) +
                                 ": pass --t-end " + format_full(pub->t) + ")"
                           : std::string(" (pass --reference METHOD, e.g. cvode_bdf)")));
  }
  c.numerical = req;
  c.numerical.method = c.kind == "exact" ? "exact" : c.method;
  c.check = c.numerical;
  if (c.check.rtol) *c.check.rtol /= kReferenceTightening;
  if (c.check.atol) *c.check.atol /= kReferenceTightening;
  if (sys && c.kind != "exact" && !create_method(req, c.method, req.params)->supports_adaptive()) {
    // reference_at_end runs a fixed-step method at h_fine/16: half the step.
    c.check_h_factor = 0.5;
    c.check_description = c.method + " with h = (finest h)/32 = " + format_full(h_fine / 32);
  }
  return c;
}
}  // namespace stiffbench

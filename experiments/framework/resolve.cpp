#include "experiments/framework/resolve.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>
#include <utility>

#include "core/integrator.hpp"

namespace stiffbench {

const ModelRegistry::Entry& StudyInputs::model_entry() const {
  if (const auto* e = own_models.find(model)) return *e;
  return model_registry().at(model);
}

const IntegratorRegistry::Entry* StudyInputs::find_integrator(const std::string& label) const {
  if (const auto* e = own_integrators.find(label)) return e;
  return integrator_registry().find(label);
}

const IntegratorRegistry::Entry& StudyInputs::integrator_entry(const std::string& label) const {
  if (const auto* e = own_integrators.find(label)) return *e;
  return integrator_registry().at(label);
}

std::unique_ptr<OdeSystem> StudyInputs::create_model(const Params& p,
                                                     std::set<std::string>* consumed) const {
  if (own_models.find(model)) return own_models.create(model, p, consumed);
  return model_registry().create(model, p, consumed);
}

std::unique_ptr<Integrator> StudyInputs::create_integrator(const std::string& label,
                                                           const Params& p,
                                                           std::set<std::string>* consumed) const {
  if (own_integrators.find(label)) return own_integrators.create(label, p, consumed);
  return integrator_registry().create(label, p, consumed);
}

namespace {

// The user's system as the model entry of a study (no parameters; a fresh copy per run).
void add_system_object(StudyInputs& in, const SystemFactory& system) {
  auto probe = system();
  require_input(probe != nullptr, "study target: the system factory returned no system");
  if (in.model.empty()) in.model = probe->name();
  require_input(!model_registry().find(in.model),
                "study target: '" + in.model +
                    "' is the name of a registered model; give the system another name");
  ModelRegistry::Entry entry;
  entry.info.name = in.model;
  entry.info.description = "system object given to a study";
  entry.info.mechanical = probe->as_mechanical() != nullptr;
  entry.info.exact = probe->has_exact();
  entry.info.source = "a user's system object";
  entry.built_in = false;
  entry.make = [system](const Params&) { return system(); };
  in.own_models.add(std::move(entry));
}

// A user's integrator object under its info().name, studied after the named ones.
void add_integrator_object(StudyInputs& in, const IntegratorFactory& make) {
  require_input(static_cast<bool>(make), "study target: empty integrator factory");
  auto probe = make();
  require_input(probe != nullptr, "study target: an integrator factory returned no integrator");
  IntegratorRegistry::Entry entry;
  entry.info = probe->info();
  const std::string name = entry.info.name;
  require_input(!name.empty(), "study target: an integrator object has no name");
  require_input(!integrator_registry().find(name) && !in.own_integrators.find(name),
                "study target: integrator '" + name +
                    "' is already registered (or given twice); give your method another name");
  entry.built_in = false;
  entry.make = [make](const Params&) { return make(); };
  in.own_integrators.add(std::move(entry));
  in.integrators.push_back(name);
}

// Every value of `user` a declaration takes, type- and range-checked (nothing is built).
void check_param_values(const StudyInputs& in, const std::vector<std::string>& integrators,
                        const Params& user) {
  if (in.has_model())
    resolve_params(in.model_entry().params, user, nullptr, "model '" + in.model + "'");
  for (const auto& name : integrators) {
    try {
      resolve_params(in.integrator_entry(name).params, user, nullptr, "integrator '" + name + "'");
    } catch (const BadInput& e) {
      if (integrators.size() < 2) throw;
      throw BadInput(std::string(e.what()) +
                     "; --param applies to every integrator of the study: to set a parameter "
                     "for some methods only, give them as variants, e.g. '" +
                     name + "{key=value}' beside '" + name + "'");
    }
  }
}

// Work vectors of a run: the integrators' stages and workspaces (Radau5: 3 complex stages and
// Newton vectors; extrapolation-free), the driver's outputs and the model's scratch; generous.
constexpr double kWorkVectors = 48;
// Sparse matrices: value + index (12 bytes) for the Jacobian, the iteration matrix and an LU
// or Cholesky factor with fill (x4).
constexpr double kSparseCopies = 6;

bool uses_dense(const Params& p) {
  auto is = [&](const char* key, std::initializer_list<const char*> values) {
    if (!p.contains(key)) return false;
    for (const char* v : values)
      if (p.values().at(key) == v) return true;
    return false;
  };
  return is("linear_solver", {"dense_lu", "dense"}) || is("jacobian", {"fd_dense"});
}
}  // namespace

StudyInputs resolve_inputs(const StudyTarget& target, const std::vector<std::string>& helpers,
                           const std::string& base) {
  StudyInputs in;
  in.model = target.model;
  in.params = target.params;
  // Method files and variants are registered process-wide once and replaced by their labels.
  in.integrators = resolve_integrator_tokens(target.integrators, base);
  if (target.objects.system) add_system_object(in, target.objects.system);
  // Look the model and the names up first so an unknown name is reported as such.
  if (in.has_model()) in.model_entry();
  for (const auto& name : in.integrators) in.integrator_entry(name);
  for (const auto& make : target.objects.integrators) add_integrator_object(in, make);
  std::vector<std::string> all = in.integrators;
  for (const auto& h : resolve_integrator_tokens(helpers, base)) {
    in.integrator_entry(h);
    if (std::find(all.begin(), all.end(), h) == all.end()) all.push_back(h);
  }
  check_param_values(in, all, in.params);
  if (in.has_model()) {
    check_run_size(in, all, in.params);
    in.memory = estimate_run_memory(in, all, in.params);
  }
  return in;
}

Setup make_setup(const StudyInputs& in, const std::vector<std::string>& integrators,
                 const Params& user) {
  Setup s;
  check_param_values(in, integrators, user);
  check_run_size(in, integrators, user);
  std::set<std::string> consumed;
  std::vector<std::string> keys;
  // "model 'kepler' takes e, gm; integrator 'radau5' takes rtol, ..." for the unknown-key message.
  auto takes = [&keys](const std::string& what, const std::vector<ParamSpec>& declared) {
    std::vector<std::string> own;
    for (const auto& p : declared) own.push_back(p.key);
    keys.insert(keys.end(), own.begin(), own.end());
    return what + " takes " + (own.empty() ? "no parameters" : join(own));
  };
  std::string accepted = takes("model '" + in.model + "'", in.model_entry().params);
  s.model = in.create_model(user, &consumed);
  for (const auto& name : integrators) {
    s.integrators.push_back(in.create_integrator(name, user, &consumed));
    check_compatible(s.integrators.back()->info(), *s.model);
    const auto& declared = in.integrator_entry(name).params;
    if (!declared.empty()) accepted += "; " + takes("integrator '" + name + "'", declared);
  }
  check_all_consumed(user, consumed, accepted, keys);
  return s;
}

Setup make_setup(const StudyInputs& in) { return make_setup(in, in.integrators, in.params); }

Setup make_setup(const std::string& model, const std::vector<std::string>& integrators,
                 const Params& user) {
  StudyTarget t;
  t.model = model;
  t.params = user;
  t.integrators = integrators;
  const StudyInputs in = resolve_inputs(t);
  return make_setup(in, in.integrators, user);
}

RunMemory estimate_run_memory(const std::string& model, const std::vector<std::string>& integrators,
                              const Params& user) {
  StudyInputs in;
  in.model = model;
  const std::vector<std::string> labels = resolve_integrator_tokens(integrators);
  return estimate_run_memory(in, labels, user);
}

RunMemory estimate_run_memory(const StudyInputs& in, const std::vector<std::string>& integrators,
                              const Params& user) {
  RunMemory m;
  if (!in.has_model()) return m;
  const std::string& model = in.model;
  const auto& entry = in.model_entry();
  if (!entry.info.size) return m;
  // The model's parameters with defaults; a value that does not parse is reported here exactly
  // as the model's creation would report it.
  m.model = entry.info.size(resolve_params(entry.params, user, nullptr, "model '" + model + "'"));
  const double n = m.model.dimension;
  m.state_bytes = kWorkVectors * 8.0 * n;
  for (const auto& name : integrators) {
    const auto& ie = in.integrator_entry(name);
    if (ie.info.family != Family::implicit && ie.info.family != Family::imex &&
        ie.info.family != Family::reference)
      continue;
    Params ip = resolve_params(ie.params, user, nullptr, "integrator '" + name + "'");
    if (const std::optional<VariantOf> v = variant_of(name))
      for (const auto& [key, value] : v->fixed.values()) ip.set(key, value);
    m.jacobian_bytes = std::max(m.jacobian_bytes, kSparseCopies * 12.0 * m.model.jacobian_nonzeros);
    if (uses_dense(ip)) {
      // Jacobian, iteration matrix and LU factor: three n x n doubles (Radau5's complex system
      // is of the same order).
      const double dense = 3.0 * 8.0 * n * n;
      if (dense > m.dense_bytes) {
        m.dense_bytes = dense;
        m.dense_integrator = name;
      }
    }
  }
  return m;
}

void check_run_size(const StudyInputs& in, const std::vector<std::string>& integrators,
                    const Params& user) {
  const RunMemory m = estimate_run_memory(in, integrators, user);
  const std::string& model = in.model;
  if (m.model.dimension <= 0) return;
  char dim[64];
  std::snprintf(dim, sizeof dim, "%.4g", m.model.dimension);
  const std::string what =
      "model '" + model + "' with " + m.model.driver + " has " + dim + " unknowns";
  require_input(m.model.dimension <= kMaxDimension,
                what + ", more than the largest supported system (" +
                    std::to_string(static_cast<long long>(kMaxDimension)) +
                    " unknowns: sparse matrices index with 32-bit integers); reduce " +
                    m.model.driver);
  std::string source;
  const double limit = memory_limit(&source);
  if (limit <= 0) return;  // unknown available memory and no --max-memory
  if (m.dense_bytes > 0 && m.total() > limit) {
    throw BadInput(what + ": integrator '" + m.dense_integrator +
                   "' with dense linear algebra would need about " + format_bytes(m.total()) +
                   " (dense matrices " + format_bytes(m.dense_bytes) + "), more than the limit " +
                   format_bytes(limit) + " (" + source +
                   "); use a sparse or matrix-free option instead (--param linear_solver=auto, "
                   "sparse_lu, klu, cg or gmres; jacobian=auto, analytic or matrix_free) or "
                   "reduce " +
                   m.model.driver);
  }
  require_input(m.total() <= limit, what + ": the run would need about " + format_bytes(m.total()) +
                                        " (model " + format_bytes(m.model.model_bytes) +
                                        ", state and work vectors " + format_bytes(m.state_bytes) +
                                        (m.jacobian_bytes > 0 ? ", Jacobian and factors " +
                                                                    format_bytes(m.jacobian_bytes)
                                                              : std::string()) +
                                        "), more than the limit " + format_bytes(limit) + " (" +
                                        source + "); reduce " + m.model.driver);
}

}  // namespace stiffbench

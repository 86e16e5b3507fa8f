#include "experiments/catalog.hpp"

#include <set>

#include "integrators/method_notes.hpp"
#include "integrators/register.hpp"
#include "models/register.hpp"

namespace stiffbench {

namespace {

constexpr const char* kRegisteredSystem = "user system (register_system)";

ModelRegistry& mutable_model_registry() {
  static ModelRegistry reg = [] {
    ModelRegistry r("model");
    register_problem_models(r);
    register_mass_spring_models(r);
    register_sph_models(r);
    register_grid_models(r);
    return r;
  }();
  return reg;
}

IntegratorRegistry& mutable_integrator_registry() {
  static IntegratorRegistry reg = [] {
    IntegratorRegistry r("integrator");
    register_explicit_integrators(r);
    register_symplectic_integrators(r);
    register_implicit_integrators(r);
    register_graphics_integrators(r);
    register_splitting_integrators(r);
    register_reference_integrators(r);
    annotate_built_in_integrators(r);
    return r;
  }();
  return reg;
}

}  // namespace

const ModelRegistry& model_registry() { return mutable_model_registry(); }
const IntegratorRegistry& integrator_registry() { return mutable_integrator_registry(); }

void register_model(ModelRegistry::Entry entry) {
  entry.built_in = false;
  mutable_model_registry().add(std::move(entry));
}

std::string register_system(SystemFactory factory, std::string name) {
  require_input(static_cast<bool>(factory), "register_system: empty factory");
  auto probe = factory();
  require_input(probe != nullptr, "register_system: the factory returned no system");
  if (name.empty()) name = probe->name();
  if (const auto* e = model_registry().find(name))
    require_input(!e->built_in && e->info.source == kRegisteredSystem,
                  "register_system: '" + name + "' is already a model; choose another name");
  ModelRegistry::Entry entry;
  entry.info.name = name;
  entry.info.description = "system object given to a study";
  entry.info.mechanical = probe->as_mechanical() != nullptr;
  entry.info.exact = probe->has_exact();
  entry.info.source = kRegisteredSystem;
  entry.built_in = false;
  entry.make = [f = std::move(factory)](const Params&) { return f(); };
  mutable_model_registry().add_or_replace(std::move(entry));
  return name;
}

void register_integrator(IntegratorRegistry::Entry entry) {
  entry.built_in = false;
  mutable_integrator_registry().add(std::move(entry));
}

Setup make_setup(const std::string& model, const std::vector<std::string>& integrators,
                 const Params& user) {
  Setup s;
  std::set<std::string> consumed;
  std::string accepted = model_registry().accepted_keys(model);
  // Look every name up before creating anything, so the first error is the unknown name.
  for (const auto& name : integrators) integrator_registry().at(name);
  s.model = model_registry().create(model, user, &consumed);
  for (const auto& name : integrators) {
    s.integrators.push_back(integrator_registry().create(name, user, &consumed));
    check_compatible(s.integrators.back()->info(), *s.model);
    if (!integrator_registry().at(name).params.empty())
      accepted += "; " + integrator_registry().accepted_keys(name);
  }
  check_all_consumed(user, consumed, accepted);
  return s;
}

std::vector<std::string> split_list(const std::string& s, const std::string& flag) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = s.find(',', start);
    const std::string item =
        s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    require_input(!item.empty(), flag + ": empty name in '" + s + "'");
    out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace stiffbench

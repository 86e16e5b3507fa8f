// What a study runs on, resolved once at the edge. The command line, a spec file or a program
// names a model, integrators (names, method-file paths, variants) and parameters, or hands over
// its own system and integrator objects; resolve_inputs() turns that into one StudyInputs value:
// the model's factory, the integrators' factories under the labels tables show, the user's
// parameters checked against them, the run-size verdict and the method-file records. Every study
// takes that value; nothing is looked up by a token again, and no object is registered anywhere.
//
// A library user builds the same value from names or objects:
//
//   StudyTarget t;
//   t.objects.system = [] { return std::make_unique<MySystem>(); };
//   t.integrators = {"radau5", "my_esdirk.toml{newton=full}"};
//   const StudyInputs in = resolve_inputs(t);
//   const WorkPrecisionResult r = run_work_precision(in, spec, &std::cerr);
#pragma once

#include <memory>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "core/registry_types.hpp"
#include "experiments/framework/catalog.hpp"

namespace stiffbench {

// A user's own system and integrator objects (nothing is registered by name).
struct StudyObjects {
  // The system: a fresh copy per run. Its results carry the target's model name when given,
  // else the system's name(); that name must not be a registered model's.
  SystemFactory system;
  // Integrators, run after the target's named ones under their info().name.
  std::vector<IntegratorFactory> integrators;
  bool empty() const { return !system && integrators.empty(); }
};

// What was said: names as the user typed them, and objects.
struct StudyTarget {
  std::string model;                     // a registered model (or the name of `system`)
  Params params;                         // model and integrator parameters (--param)
  std::vector<std::string> integrators;  // names, method-file paths and variants, in order
  StudyObjects objects;                  // a user's own system and integrators (optional)
};

// What a study runs on: the result of resolve_inputs().
struct StudyInputs {
  std::string model;                     // the name tables show ("" when there is none)
  Params params;                         // the user's parameters (--param)
  std::vector<std::string> integrators;  // the studied integrators' labels, in order
  RunMemory memory;                      // the run-size estimate that was checked

  // The model's entry (registered, or made from the user's system object).
  const ModelRegistry::Entry& model_entry() const;
  bool has_model() const { return !model.empty(); }
  // An integrator by label: the study's own (its integrators, objects and helpers) first, then
  // the process-wide registry (for the fixed methods a study picks itself, e.g. a reference).
  // BadInput naming an unknown one.
  const IntegratorRegistry::Entry& integrator_entry(const std::string& label) const;
  const IntegratorRegistry::Entry* find_integrator(const std::string& label) const;

  // A fresh model created with `params` (usually `this->params` or a study's copy of it; the
  // keys the model declares are added to `consumed`).
  std::unique_ptr<OdeSystem> create_model(const Params& params,
                                          std::set<std::string>* consumed = nullptr) const;
  // A fresh integrator `label` with its declared keys taken from `params`.
  std::unique_ptr<Integrator> create_integrator(const std::string& label, const Params& params,
                                                std::set<std::string>* consumed = nullptr) const;

  // `spec` (a study's spec JSON) with the method files and variants of its integrators recorded
  // (with_method_files).
  nlohmann::json record(nlohmann::json spec) const { return with_method_files(std::move(spec)); }

  ModelRegistry own_models{"model"};                 // the user's system, when given
  IntegratorRegistry own_integrators{"integrator"};  // the user's integrator objects
};

// Resolves `target`: method-file tokens and variants registered and replaced by their labels
// (relative paths from `base`), the user's objects wrapped as entries, every name checked, the
// parameters type- and range-checked against the model and the integrators, and the run size
// checked (check_run_size). `helpers` are further integrators the study consumes (a reference
// method): resolved and checked the same way, not studied. BadInput for anything wrong, before
// anything runs.
StudyInputs resolve_inputs(const StudyTarget& target, const std::vector<std::string>& helpers = {},
                           const std::string& base = "");

// The inputs a study spec names (its model, params and integrators fields; a study of methods
// alone, e.g. region, has integrators only), with a user's objects when given, resolved.
template <class Spec>
StudyInputs inputs_of(const Spec& spec, StudyObjects objects = {}) {
  StudyTarget t;
  if constexpr (requires { spec.model; }) t.model = spec.model;
  if constexpr (requires { spec.params; }) t.params = spec.params;
  t.integrators = spec.integrators;
  t.objects = std::move(objects);
  return resolve_inputs(t);
}
// `spec` with its model, params and integrators fields (those it has) taken from `in` (what it
// records).
template <class Spec>
Spec with_inputs(Spec spec, const StudyInputs& in) {
  if constexpr (requires { spec.model; }) spec.model = in.model;
  if constexpr (requires { spec.params; }) spec.params = in.params;
  spec.integrators = in.integrators;
  return spec;
}

struct Setup {
  std::unique_ptr<OdeSystem> model;
  std::vector<std::unique_ptr<Integrator>> integrators;
};

// Creates the model and each of `integrators` (labels of `in`), offering every key of `user` to
// each of them; a key none of them declares is BadInput naming it. Each integrator is checked
// against the model, so an incompatible pair is reported before any run starts, and the run size
// is checked for these parameters.
Setup make_setup(const StudyInputs& in, const std::vector<std::string>& integrators,
                 const Params& user);
// make_setup(in, in.integrators, in.params).
Setup make_setup(const StudyInputs& in);
// The same from names (resolve_inputs first): for `solve` and programs.
Setup make_setup(const std::string& model, const std::vector<std::string>& integrators,
                 const Params& user);

// The memory estimate for `in`'s model run by `integrators` with `user`'s parameters (a model
// without a size estimate, registered from outside, gives dimension 0 and is not checked).
RunMemory estimate_run_memory(const StudyInputs& in, const std::vector<std::string>& integrators,
                              const Params& user);
RunMemory estimate_run_memory(const std::string& model, const std::vector<std::string>& integrators,
                              const Params& user);
// BadInput naming the parameter, the memory the run would need and the limit, when it exceeds
// the limit or kMaxDimension; dense linear algebra on a large system is refused with a pointer
// to the sparse and matrix-free options.
void check_run_size(const StudyInputs& in, const std::vector<std::string>& integrators,
                    const Params& user);

}  // namespace stiffbench

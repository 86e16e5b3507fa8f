// Registry types for models and integrators. The layers fill them (models/register.hpp,
// integrators/register.hpp); experiments/framework/catalog.hpp holds the process-wide instances.
#pragma once

#include "core/integrator.hpp"
#include "core/ode_system.hpp"
#include "core/registry.hpp"

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace stiffbench {

// What a model of given parameters would allocate, estimated from the parameters alone (before
// anything is built), so that a run too large for the machine is refused up front
// (experiments/framework/catalog.hpp, check_run_size). Doubles: n = 1e9 cubed must not overflow.
struct ModelSize {
  double dimension = 0;          // state size (unknowns)
  double model_bytes = 0;        // the model's own data (springs, particles, neighbour lists)
  double jacobian_nonzeros = 0;  // nonzeros of its sparse Jacobian (0: none or dense only)
  std::string driver;            // the parameter(s) the size follows, e.g. "n=1000 m=1000"
};
using ModelSizeEstimate = std::function<ModelSize(const Params&)>;

// A model's entry is complete when it is registered (nothing patches it afterwards); it is built
// with designated initialisers, e.g. {.name = "cloth", .description = ..., .mechanical = true,
// .source = ..., .size = ..., .rest_state = ...}, the flags false unless given.
struct ModelInfo {
  std::string name;
  std::string description;
  bool mechanical = false;  // y = [x; v]
  bool exact = false;       // provides the exact solution
  std::string source;       // where the equations and reference values come from
  // Every built-in model has one (a test checks); a model registered from outside without one
  // is not size-checked.
  ModelSizeEstimate size = nullptr;
  // Parameter values that make the initial state an equilibrium at rest (no load, no
  // displacement), e.g. cloth {gravity 0, perturbation 0}: the per-mode analysis of
  // `fidelity` linearises there and applies those the user did not set. Empty: the defaults
  // already start at rest, or the model has no such state.
  std::vector<std::pair<std::string, std::string>> rest_state = {};
};

using ModelRegistry = Registry<OdeSystem, ModelInfo>;
using IntegratorRegistry = Registry<Integrator, MethodInfo>;

// Both registries are instantiated once, in the library (core/registry_types.cpp): a program
// that creates models and integrators by name does not compile the members again.
extern template class Registry<OdeSystem, ModelInfo>;
extern template class Registry<Integrator, MethodInfo>;

}  // namespace stiffbench

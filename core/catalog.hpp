// Registry types for models and integrators. The layers fill them (models/register.hpp,
// integrators/register.hpp); experiments/catalog.hpp holds the process-wide instances.
#pragma once

#include "core/integrator.hpp"
#include "core/ode_system.hpp"
#include "core/registry.hpp"

namespace stiffbench {

struct ModelInfo {
  std::string name;
  std::string description;
  bool mechanical = false;  // y = [x; v]
  bool exact = false;       // provides the exact solution
  std::string source;       // where the equations and reference values come from
};

using ModelRegistry = Registry<OdeSystem, ModelInfo>;
using IntegratorRegistry = Registry<Integrator, MethodInfo>;

}  // namespace stiffbench

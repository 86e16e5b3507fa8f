// Helpers shared by the test files: create registered integrators and models by name with
// "key=value" parameters, as the command line does.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "experiments/framework/catalog.hpp"

namespace stiffbench::testing_support {

inline std::unique_ptr<Integrator> make(const std::string& name,
                                        const std::vector<std::string>& params = {}) {
  return integrator_registry().create(name, Params::from_assignments(params));
}

inline std::unique_ptr<OdeSystem> model(const std::string& name,
                                        const std::vector<std::string>& params = {}) {
  return model_registry().create(name, Params::from_assignments(params));
}

}  // namespace stiffbench::testing_support

// Registration of every model with its parameters (defaults and meaning for `describe`).
#pragma once

#include "core/registry_types.hpp"

namespace stiffbench {

void register_problem_models(ModelRegistry& reg);
void register_mass_spring_models(ModelRegistry& reg);
void register_sph_models(ModelRegistry& reg);
void register_grid_models(ModelRegistry& reg);

}  // namespace stiffbench

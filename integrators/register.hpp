// Registration of the hand-written integrators, in the order `list integrators` shows them.
#pragma once

#include "core/registry_types.hpp"

namespace stiffbench {

void register_explicit_integrators(IntegratorRegistry& reg);
void register_symplectic_integrators(IntegratorRegistry& reg);
void register_implicit_integrators(IntegratorRegistry& reg);
// XPBD and projective dynamics (integrators/graphics/): mass-spring networks only.
void register_graphics_integrators(IntegratorRegistry& reg);
// Operator-splitting schemes for particular model classes (Family::operator_splitting, printed
// "splitting"; stable_fluids: grid fluids).
void register_operator_splitting_integrators(IntegratorRegistry& reg);
// The library references (integrators/reference/).
void register_reference_integrators(IntegratorRegistry& reg);

}  // namespace stiffbench

// The Eulerian grid models' registry entries, in `list` order; each is defined beside its model
// (NAME_entry() in models/grid/NAME.cpp).
#include "models/register.hpp"

namespace stiffbench {

ModelRegistry::Entry heat_2d_entry();
ModelRegistry::Entry fluid_2d_entry();

void register_grid_models(ModelRegistry& reg) {
  reg.add(heat_2d_entry());
  reg.add(fluid_2d_entry());
}

}  // namespace stiffbench

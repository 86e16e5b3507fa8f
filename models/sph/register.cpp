// The SPH scenes' registry entries, in `list` order; each is defined beside its scene
// (models/sph/scenes.cpp). The physics and its options are documented in
// models/sph/sph_fluid.hpp.
#include "models/register.hpp"

namespace stiffbench {

ModelRegistry::Entry sph_dam_break_entry(int dim);
ModelRegistry::Entry sph_tank_entry(int dim);
ModelRegistry::Entry sph_drop_entry();

void register_sph_models(ModelRegistry& reg) {
  reg.add(sph_dam_break_entry(2));
  reg.add(sph_dam_break_entry(3));
  reg.add(sph_tank_entry(2));
  reg.add(sph_tank_entry(3));
  reg.add(sph_drop_entry());
}

}  // namespace stiffbench

// The mass-spring models' registry entries, in `list` order; each is defined beside its builder
// (models/mass_spring/builders.cpp). Models and their physics: models/mass_spring/builders.hpp.
#include "models/register.hpp"

namespace stiffbench {

ModelRegistry::Entry spring_chain_entry();
ModelRegistry::Entry cloth_entry();
ModelRegistry::Entry soft_cube_entry();
ModelRegistry::Entry pendulum_chain_entry();

void register_mass_spring_models(ModelRegistry& reg) {
  reg.add(spring_chain_entry());
  reg.add(cloth_entry());
  reg.add(soft_cube_entry());
  reg.add(pendulum_chain_entry());
}

}  // namespace stiffbench

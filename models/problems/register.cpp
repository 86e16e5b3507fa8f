// The problems' registry entries, in `list` order; each is defined beside its model
// (NAME_entry() in models/problems/NAME.cpp).
#include "models/register.hpp"

namespace stiffbench {

ModelRegistry::Entry dahlquist_entry();
ModelRegistry::Entry harmonic_oscillator_entry();
ModelRegistry::Entry kepler_entry();
ModelRegistry::Entry pendulum_entry();
ModelRegistry::Entry prothero_robinson_entry();
ModelRegistry::Entry robertson_entry();
ModelRegistry::Entry hires_entry();
ModelRegistry::Entry van_der_pol_entry();
ModelRegistry::Entry orego_entry();
ModelRegistry::Entry e5_entry();
ModelRegistry::Entry pollution_entry();
ModelRegistry::Entry kaps_entry();
ModelRegistry::Entry advection_diffusion_entry();
ModelRegistry::Entry brusselator_entry();

void register_problem_models(ModelRegistry& reg) {
  reg.add(dahlquist_entry());
  reg.add(harmonic_oscillator_entry());
  reg.add(kepler_entry());
  reg.add(pendulum_entry());
  reg.add(prothero_robinson_entry());
  // Classic stiff test problems (Hairer & Wanner II §IV.10; IVP test set of Mazzia &
  // Magherini). Each model's end_time() is the literature end time, used when --t-end is
  // omitted.
  reg.add(robertson_entry());
  reg.add(hires_entry());
  reg.add(van_der_pol_entry());
  reg.add(orego_entry());
  reg.add(e5_entry());
  reg.add(pollution_entry());
  reg.add(kaps_entry());
  reg.add(advection_diffusion_entry());
  reg.add(brusselator_entry());
}

}  // namespace stiffbench

// The per-mode part of the fidelity study (experiments/studies/fidelity.hpp: "Per mode on a
// mechanical model"): the linearised modes of the model at rest and one run per integrator and
// step projected on them. Private to the study.
#pragma once

#include <iosfwd>
#include <vector>

#include "core/ode_system.hpp"
#include "core/types.hpp"
#include "experiments/studies/fidelity.hpp"

namespace stiffbench::fidelity_internal {

struct ModalBasis {
  Vec x0;
  std::vector<Index> free;  // dofs not fixed
  Vec mass;                 // of the free dofs
  Mat phi;                  // free × modes, M-orthonormal columns
  Vec omega;                // per mode
  double omega_max = 0.0;   // the system's fastest mode
};

struct ModalSetup {
  Setup setup;
  const MechanicalSystem* mech = nullptr;
  ModalBasis basis;
};

// The model of `in`, its integrators and its modes, checked and computed before anything runs:
// BadInput for a model that is not mechanical, not at rest or damped.
ModalSetup prepare_modes(const StudyInputs& in, const FidelitySpec& spec);
// One run of every integrator at each step (spec.h, else nu = 0.1 at the lowest and nu = 2 at the
// highest selected mode) into out.modes and out.mode_steps_used.
void run_modes(const StudyInputs& in, const FidelitySpec& spec, const ModalSetup& m,
               FidelityResult& out, std::ostream* progress);

}  // namespace stiffbench::fidelity_internal

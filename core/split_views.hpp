// The two parts of an additive split f = f_E + f_I (OdeSystem::has_imex_split) as systems of
// their own, so that any integrator can advance one part: the IMEX Runge–Kutta stages solve
// z = ψ + hγ f_I(t, z) with the implicit methods' Newton (ImplicitCore) on the implicit part's
// view, and the operator-splitting integrators (lie, strang) run a named sub-integrator on each
// view.
//
//   explicit_part_view(sys)   rhs = f_E; no Jacobian; stiffness() = the model's
//                             explicit_part_spectrum() radius. A plain OdeSystem (for a
//                             mechanical model f_E = [0; a_E] is not of the form [v; a]).
//   implicit_part_view(sys)   rhs = f_I, Jacobian J_I (when the model has it). For a mechanical
//                             model a MechanicalSystem with a = a_I and force Jacobians K_I, D_I,
//                             the masses, pinned dofs and symmetry of the model, so implicit
//                             methods keep their velocity-form linear solves.
//
// Every evaluation goes through the model's public counting calls (rhs_explicit_part, ...), so
// the model's counters — which the driver reads — count them (in f_evals and in fe_evals or
// fi_evals); the views' own counters are not used. Constraints and projections stay with the
// model (the driver projects after the whole step). A view refers to the model: it must not
// outlive it. BadInput naming the model when it has no split.
#pragma once

#include <memory>

#include "core/ode_system.hpp"

namespace stiffbench {

std::unique_ptr<OdeSystem> explicit_part_view(const OdeSystem& sys);
std::unique_ptr<OdeSystem> implicit_part_view(const OdeSystem& sys);

// BadInput "<who> needs a model with an additive split f = f_E + f_I; model 'M' has none (...)"
// unless sys.has_imex_split().
void require_split(const OdeSystem& sys, const std::string& who);

}  // namespace stiffbench

// HolonomicConstraints: the optional face of a mechanical system's holonomic constraints
// g(x) = 0 (m scalar equations on the positions), for methods that enforce them themselves
// (rattle, integrators/symplectic/rattle.hpp). A MechanicalSystem offers it through
// MechanicalSystem::holonomic_constraints() (nullptr: none offered); integrators check that
// through Requirements::constraints, never by casting to a model class.
//
// The constrained equations of motion (Hairer, Lubich & Wanner, Geometric Numerical
// Integration, 2nd ed., VII.1):
//   x' = v,   M v' = F(t, x) - G(x)ᵀ λ,   g(x) = 0,
// with G = ∂g/∂x (m × dofs) and the Lagrange multipliers λ. The system's acceleration() is the
// unconstrained part M⁻¹F; the inverse masses are 1/MechanicalSystem::masses() with the weight of
// MechanicalSystem::fixed_dofs() set to 0 (pinned points never move). The constraints are meant to
// be independent (G of full row rank on the manifold, so G M⁻¹ Gᵀ is nonsingular); a model leaves
// out constraints that cannot move (all their dofs fixed).
//
// This is not the OdeSystem::project() hook: a model may offer both (the mass-spring network
// does); methods that enforce the constraints themselves are not followed by the driver's
// projection (core/driver.cpp).
#pragma once

#include "core/types.hpp"

namespace stiffbench {

class HolonomicConstraints {
 public:
  virtual ~HolonomicConstraints() = default;

  // m, the number of scalar constraints.
  virtual Index constraint_count() const = 0;

  // g(x), m entries; x has dofs() entries.
  virtual void constraint_values(CVecRef x, VecRef g) const = 0;

  // G(x) = ∂g/∂x, m × dofs, sparse. Its pattern is the same at every x: when `jac` already holds
  // it (from a previous call) only the values change, without allocation.
  virtual void constraint_jacobian(CVecRef x, SparseMat& jac) const = 0;
};

}  // namespace stiffbench

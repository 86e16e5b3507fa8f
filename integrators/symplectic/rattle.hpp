// RATTLE (Andersen 1983, J. Comput. Phys. 52, 24–34; Hairer, Lubich & Wanner, Geometric
// Numerical Integration, 2nd ed., §VII.1): velocity Verlet for a mechanical system with holonomic
// constraints g(x) = 0 (core/constraints.hpp), M x'' = F(x) - G(x)ᵀ λ. With a = M⁻¹F the system's
// acceleration, W = M⁻¹ (0 on fixed dofs) and G = ∂g/∂x, one step is
//   v_{n+½} = v_n + ½h (a(x_n) - W G(x_n)ᵀ λ_n)
//   x_{n+1} = x_n + h v_{n+½},                    g(x_{n+1}) = 0          (positions)
//   v_{n+1} = v_{n+½} + ½h (a(x_{n+1}) - W G(x_{n+1})ᵀ μ_n),  G(x_{n+1}) v_{n+1} = 0 (velocities).
// It is second order, symmetric and symplectic on the constraint manifold (Leimkuhler & Skeel
// 1994), so the energy error stays bounded over long runs instead of drifting, and both constraints
// hold at every step up to the solver tolerance.
//
// Positions: with the free drift x̄ = x_n + h v_n + ½h² a(x_n) and Λ = ½h² λ_n,
// x_{n+1} = x̄ - W G_nᵀ Λ, and Newton on the multipliers solves g(x̄ - W G_nᵀ Λ) = 0:
//   (G(x^k) W G_nᵀ) ΔΛ = g(x^k),  Λ ← Λ + ΔΛ,
// a nonsymmetric m × m sparse system (G at two positions) factored by sparse LU each iteration;
// quadratic convergence, typically 2–3 iterations per step. It stops when
// max|g| <= constraint_tol · max(1, ‖x‖∞) (the relative form keeps the test above the round-off
// floor, a few ε|x|, of evaluating g); after newton_max_iter iterations without that the step
// fails with Status::newton_failed. Then v_{n+½} = v_n + ½h a(x_n) - W G_nᵀ Λ / h (not the
// difference quotient, which would lose ε|x|/h).
// Velocities: the condition is linear, (G W Gᵀ) μ' = G v̄ with v̄ = v_{n+½} + ½h a(x_{n+1}) and
// v_{n+1} = v̄ - W Gᵀ μ', G = G(x_{n+1}); G W Gᵀ is symmetric positive definite for independent
// constraints (sparse LDLᵀ), refined (at most 3 solves) until max|G v| <= constraint_tol ·
// max(1, ‖v‖∞).
//
// One acceleration evaluation per step (a(x_{n+1}) and G(x_{n+1}) are reused by the next step
// when it starts where this one ended). The system must offer its constraints through
// MechanicalSystem::holonomic_constraints() and have velocity-independent forces
// (Requirements: check_compatible refuses others with BadInput). Because the method enforces the
// constraints itself, the fixed-step driver does not call the model's project() after its steps
// (core/driver.cpp): the state is RATTLE's own. A system with m = 0 active constraints gets
// velocity Verlet. The initial state should be consistent (g(x_0) = 0, G(x_0) v_0 = 0); the first
// step makes the state consistent otherwise. Unlike the unconstrained Verlet family, a step
// allocates (Eigen's sparse products and factorisations of the m × m systems); the allocation
// test (tests/integrators/test_allocations.cpp) runs on unconstrained models, which rattle refuses.
#pragma once

#include <memory>
#include <vector>

#include "core/constraints.hpp"
#include "core/integrator.hpp"
#include "core/params.hpp"

namespace stiffbench {

struct RattleOptions {
  double constraint_tol = 1e-14;  // relative, see the header comment
  int newton_max_iter = 20;
};

std::vector<ParamSpec> rattle_param_specs();
RattleOptions read_rattle_options(const Params& p);

class Rattle final : public Integrator {
 public:
  explicit Rattle(RattleOptions opt);
  ~Rattle() override;
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;

 private:
  // v ← v - W Gᵀ μ with G W Gᵀ μ = G v at G = g_new_ (the velocity condition).
  bool project_velocity(VecRef v, SolveStats& stats);

  RattleOptions opt_;
  const MechanicalSystem* mech_ = nullptr;
  const HolonomicConstraints* cons_ = nullptr;
  Vec w_;  // inverse masses per dof, 0 on fixed dofs
  Vec acc_, x_bar_, x_last_, g_val_, lambda_, step_;
  SparseMat g_old_, g_new_;  // G(x_n), G(x_{n+1})
  SparseMat wgt_;            // W G(x_n)ᵀ (dofs × m)
  // Eigen's SparseLU and SimplicialLDLT, defined in rattle.cpp: their headers stay out of this
  // installed header and of the files that include it.
  struct Solvers;
  std::unique_ptr<Solvers> solvers_;
  bool started_ = false;
};

}  // namespace stiffbench

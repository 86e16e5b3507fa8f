// Baraff & Witkin (SIGGRAPH 1998) semi-implicit Euler for mechanical systems, in velocity form:
//   (M - h D_f - h² K_f) Δv = h (f + h K_f v),   v⁺ = v + Δv,   x⁺ = x + h v⁺,
// with forces f = M a, K_f = M K = ∂f/∂x, D_f = M D = ∂f/∂v, all at (t, x, v) — one
// linearisation of backward Euler, so order 1. It is linearly implicit Euler (I - hJ) k = h f
// solved in velocity form, and uses the same solver (integrators/solvers/velocity_form.hpp): the
// matrix has the dofs' dimension, pinned dofs are eliminated (filtered) so it stays symmetric for
// symmetric force Jacobians (mass-spring networks without dashpots), and `auto` takes ldlt up to
// 2000 dofs and cg with a Jacobi preconditioner above.
// The single Krylov solve stops at the relative residual krylov_tol = 1e-6 by default (the solve
// error then stays far below the method's O(h) error per step), warm-started from the previous
// step's Δv.
// Cost per step: one acceleration, one K and D evaluation (counted as one Jacobian), one matrix
// assembly and factorisation (or Krylov set-up) and one solve.
#pragma once

#include "core/integrator.hpp"
#include "integrators/solvers/newton.hpp"
#include "integrators/solvers/velocity_form.hpp"

namespace stiffbench {

class BaraffWitkin final : public Integrator {
 public:
  explicit BaraffWitkin(ImplicitOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  // On a linear oscillator the step is exactly backward Euler's (R(z) = 1/(1 − z)).
  std::optional<LinearStability> linear_stability() const override {
    LinearStability s = rosenbrock_stability(Mat::Zero(1, 1), Mat::Ones(1, 1), Vec::Ones(1));
    s.kind = "linearly implicit Euler (velocity form)";
    return s;
  }
  const VelocityFormSolver& solver() const { return solver_; }

 private:
  ImplicitOptions opt_;
  const MechanicalSystem* mech_ = nullptr;
  VelocityFormSolver solver_;
  Vec r_, k_;
};

}  // namespace stiffbench

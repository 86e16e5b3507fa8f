// Baraff & Witkin (SIGGRAPH 1998) semi-implicit Euler for mechanical systems, in velocity form:
//   (M - h D_f - h² K_f) Δv = h (f + h K_f v),   v⁺ = v + Δv,   x⁺ = x + h v⁺,
// with forces f = M a, K_f = M K = ∂f/∂x, D_f = M D = ∂f/∂v, all at (t, x, v) — one
// linearisation of backward Euler, so order 1. The matrix has the dofs' dimension (half the
// first-order system) and is symmetric when M K and M D are (mass-spring networks without
// pins); with SPD -K_f and -D_f it is SPD and ldlt or cg apply (REFERENCES.md). Pinned dofs with
// zero K and D rows get the row M_ii Δv_i = h M_ii a_i = 0; their columns stay (free points feel
// their pinned neighbours), so with pins the matrix is not symmetric and ldlt/cg refuse
// (solver_error): use sparse_lu, bicgstab or gmres there.
// Cost per step: one acceleration, one K and D evaluation (counted as one Jacobian), one
// factorisation and one solve.
#pragma once

#include "core/integrator.hpp"
#include "integrators/implicit/implicit_core.hpp"

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

 private:
  std::vector<SparseTerm> terms(double h) const;

  ImplicitOptions opt_;
  const MechanicalSystem* mech_ = nullptr;
  std::unique_ptr<LinearSolver> solver_;
  SparseCombination a_;
  SparseMat mass_, k_, d_;
  Vec m_, acc_, rhs_, dv_;
};

}  // namespace stiffbench

// Kaps' problem (Kaps & Rentrop, "Generalized Runge–Kutta methods of order four with stepsize
// control for stiff ordinary differential equations", Numer. Math. 33, 1979; Hairer & Wanner,
// Solving ODEs II, §IV.15, the classic check of order reduction):
//   y1' = -(2 + 1/ε) y1 + y2²/ε,   y2' = y1 - y2 - y2²,   y(0) = (1, 1),   t ∈ [0, 1].
// Exact solution for every ε > 0: y1 = e^{-2t}, y2 = e^{-t} (then y2² = y1, so the 1/ε terms
// cancel: -y1/ε + y2²/ε = 0, and y1' = -2 y1, y2' = y1 - y2 - y2² = -y2).
// Parameter eps (ε > 0, default 1e-6): the stiffness knob. Autonomous.
// Jacobian [[-(2 + 1/ε), 2 y2/ε], [1, -1 - 2 y2]]; stiffness() its Gershgorin bound
// min(‖J‖₁, ‖J‖∞) (≈ 1/ε).
// Additive split (split=stiff, the only one): f_I = (-y1/ε + y2²/ε, 0) (the 1/ε terms),
// J_I = [[-1/ε, 2 y2/ε], [0, 0]]; f_E = (-2 y1, y1 - y2 - y2²), whose Jacobian
// [[-2, 0], [1, -1 - 2 y2]] has the eigenvalues -2 and -1 - 2 y2 (lower triangular):
// explicit_part_spectrum() returns max(2, |1 + 2 y2|) on the negative real axis.
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class Kaps final : public OdeSystem {
 public:
  explicit Kaps(double eps);

  std::string name() const override { return "kaps"; }
  Index dimension() const override { return 2; }
  Vec initial_state() const override { return Vec{{1.0, 1.0}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override;
  std::optional<double> stiffness(double t, CVecRef y) const override;
  std::optional<double> end_time() const override { return 1.0; }

  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override;
  bool has_implicit_part_jacobian() const override { return true; }
  std::optional<SpectrumEstimate> explicit_part_spectrum(double t, CVecRef y) const override;

  double eps() const { return eps_; }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef fe) const override;
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const override;
  void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  double eps_;
};

}  // namespace stiffbench

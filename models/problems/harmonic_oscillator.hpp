// Damped harmonic oscillator  m x'' + γ x' + k x = 0,  y = [x; v].
// Parameters m, k, gamma (γ = 0 by default: undamped), x0, v0.
// Exact solution (β = γ/2m, ω0 = √(k/m)):
//   underdamped β < ω0:  x = e^{-βt}(x0 cos ωd t + (v0 + β x0)/ωd sin ωd t),  ωd = √(ω0² - β²)
//   critical    β = ω0:  x = e^{-βt}(x0 + (v0 + β x0) t)
//   overdamped  β > ω0:  x = C1 e^{r1 t} + C2 e^{r2 t},  r1,2 = -β ± √(β² - ω0²)
// Invariant: energy E = ½ m v² + ½ k x² (conserved for γ = 0, dE/dt = -γ v² otherwise).
// K = ∂a/∂x = -k/m, D = ∂a/∂v = -γ/m; spectral radius of the Jacobian ω0 when underdamped.
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class HarmonicOscillator final : public MechanicalSystem {
 public:
  HarmonicOscillator(double m, double k, double gamma, double x0, double v0);

  std::string name() const override { return "harmonic_oscillator"; }
  Index dofs() const override { return 1; }
  Vec initial_state() const override { return Vec{{x0_, v0_}}; }
  bool autonomous() const override { return true; }
  bool velocity_dependent() const override { return gamma_ != 0.0; }
  Vec masses() const override { return Vec::Constant(1, m_); }
  bool has_force_jacobians() const override { return true; }
  void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const override;
  void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const override;
  bool symmetric_force_jacobians() const override { return true; }  // 1-dof or a Hessian
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override;
  std::vector<Invariant> invariants() const override;
  std::optional<double> stiffness(double t, CVecRef y) const override;

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override;

 private:
  double m_, k_, gamma_, x0_, v0_;
};

}  // namespace stiffbench

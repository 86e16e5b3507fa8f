// Nonlinear pendulum  θ'' = -(g/L) sin θ,  y = [θ; ω].
// Parameters g (1), length L (1), theta0 (1 rad), omega0 (0). No closed-form solution is
// provided (convergence studies use --reference METHOD).
// Invariant: energy per unit mass E = ½ L² ω² + g L (1 - cos θ).
// K = ∂a/∂θ = -(g/L) cos θ, D = 0; stiffness estimate √(g/L |cos θ|) (at least the
// small-angle frequency's order of magnitude).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class Pendulum final : public MechanicalSystem {
 public:
  Pendulum(double g, double length, double theta0, double omega0)
      : g_(g), length_(length), theta0_(theta0), omega0_(omega0) {}

  std::string name() const override { return "pendulum"; }
  Index dofs() const override { return 1; }
  Vec initial_state() const override { return Vec{{theta0_, omega0_}}; }
  bool autonomous() const override { return true; }
  bool velocity_dependent() const override { return false; }
  bool has_force_jacobians() const override { return true; }
  void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const override;
  void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const override;
  bool symmetric_force_jacobians() const override { return true; }  // 1-dof or a Hessian
  std::vector<Invariant> invariants() const override;
  std::optional<double> stiffness(double t, CVecRef y) const override;

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override;

 private:
  double g_, length_, theta0_, omega0_;
};

}  // namespace stiffbench

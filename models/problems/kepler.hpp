// Kepler two-body problem in the plane, relative coordinates, unit mass:
//   q'' = -GM q / |q|³,   y = [q1, q2, v1, v2].
// Parameters: e (eccentricity, 0 <= e < 1, default 0: circular), gm (GM = 1), a (semi-major
// axis = 1), so the period is T = 2π √(a³/GM) = 2π by default. Starts at pericentre:
//   q(0) = (a(1 - e), 0),   v(0) = (0, √(GM/a · (1 + e)/(1 - e))).
// Exact solution for every e < 1 through Kepler's equation E - e sin E = n t, n = √(GM/a³):
//   q = (a(cos E - e), a√(1-e²) sin E),   v = Ė (-a sin E, a√(1-e²) cos E),  Ė = n/(1 - e cos E).
// (Goldstein, Classical Mechanics §3.8; the same problem as SUNDIALS' kepler test.)
// Invariants: energy H = ½|v|² - GM/|q| = -GM/(2a), angular momentum L = q1 v2 - q2 v1.
// K = ∂a/∂q = -GM (I/r³ - 3 q qᵀ/r⁵); stiffness estimate √(2GM/r³) (radial eigenvalue of K).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class Kepler final : public MechanicalSystem {
 public:
  Kepler(double e, double gm, double a);

  std::string name() const override { return "kepler"; }
  Index dofs() const override { return 2; }
  Vec initial_state() const override;
  bool autonomous() const override { return true; }
  bool velocity_dependent() const override { return false; }
  bool has_force_jacobians() const override { return true; }
  void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const override;
  void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const override;
  bool symmetric_force_jacobians() const override { return true; }  // 1-dof or a Hessian
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override;
  std::vector<Invariant> invariants() const override;
  std::optional<double> stiffness(double t, CVecRef y) const override;

  double period() const;

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override;

 private:
  double e_, gm_, a_;
};

}  // namespace stiffbench

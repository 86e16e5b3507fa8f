// Brusselator with diffusion in one space dimension (the reaction A → U, B + U → V + D,
// 2U + V → 3U, U → E of Prigogine & Lefever 1968 with A = 1, B = 3), by the method of lines as in
// Hairer, Nørsett & Wanner, Solving Ordinary Differential Equations I (2nd ed., 1993), §I.16, and
// Hairer & Wanner, Solving Ordinary Differential Equations II (2nd ed., 1996), §IV.1 (the BRUSS
// problem of their §IV.10 comparisons takes N = 500, dimension 1000). For i = 1..N,
// x_i = i/(N+1), c = α (N+1)²:
//   u_i' = 1 + u_i² v_i − 4 u_i + c (u_{i−1} − 2u_i + u_{i+1}),
//   v_i' = 3 u_i − u_i² v_i + c (v_{i−1} − 2v_i + v_{i+1}),
// boundary values u_0 = u_{N+1} = 1, v_0 = v_{N+1} = 3; initial u_i = 1 + sin(2π x_i), v_i = 3;
// t ∈ [0, 10] (end_time() 10). Parameters: n (N >= 1, default 32), alpha (α > 0, default 1/50).
// The unknowns are interleaved, y = (u_1, v_1, u_2, v_2, ..., u_N, v_N), so J is banded with
// lower and upper bandwidth 2.
// Equilibrium: u ≡ 1, v ≡ 3 (the boundary values) makes every difference quotient vanish and the
// reaction terms 1 + 3 − 4 = 0 and 3 − 3 = 0, so f = 0 there. It is unstable: on the lowest
// Dirichlet mode sin(π x) the linearisation is [[2 − μ, 1], [−3, −1 − μ]] with
// μ = 4c sin²(π/(2(N+1))) ≤ απ², trace 1 − 2μ ≥ 1 − 2απ² ≈ 0.61 > 0 and determinant
// (2 − μ)(−1 − μ) + 3 = 1 − μ + μ² > 0 (an unstable focus), so solutions do not settle there.
// No exact solution and no linear invariant ((u_i + v_i)' = 1 − u_i + diffusion): the reference
// is the library's default (cvode_bdf at tight tolerance).
// Jacobian (8N − 4 entries, fixed pattern): row u_i: ∂/∂u_{i±1} = c, ∂/∂u_i = 2u_i v_i − 4 − 2c,
// ∂/∂v_i = u_i²; row v_i: ∂/∂v_{i±1} = c, ∂/∂u_i = 3 − 2u_i v_i, ∂/∂v_i = −u_i² − 2c.
// stiffness(): min(‖J‖₁, ‖J‖∞), the Gershgorin bound on the spectral radius: the diffusion part
// contributes 4c = 4α(N+1)² (its eigenvalues are −4c sin²(kπ/(2(N+1))), k = 1..N), the reaction
// part the 2×2 block's row sums |2uv − 4| + u² and |3 − 2uv| + u².
// profiles(): "brusselator" with columns x, u, v (the boundary points included).
// Non-negative components: all 2N (u and v are the concentrations of the intermediates X and Y).
// Where y >= 0 and u_i = 0, u_i' = 1 + c (u_{i−1} + u_{i+1}) > 0; where v_i = 0,
// v_i' = 3 u_i + c (v_{i−1} + v_{i+1}) >= 0; the boundary values and y(0) are >= 0, so y(t) >= 0
// for every α > 0 (the positivity criterion of core/ode_system.hpp).
#pragma once

#include <string>
#include <vector>

#include "core/ode_system.hpp"

namespace stiffbench {

class Brusselator final : public OdeSystem {
 public:
  Brusselator(int n, double alpha);

  std::string name() const override { return "brusselator"; }
  Index dimension() const override { return 2 * n_; }
  std::optional<double> end_time() const override { return 10.0; }
  Vec initial_state() const override;
  bool autonomous() const override { return true; }
  bool has_jacobian() const override { return true; }
  std::optional<double> stiffness(double t, CVecRef y) const override;
  std::vector<Profile> profiles(double t, CVecRef y) const override;
  std::vector<Index> nonnegative_components() const override { return all_components(2 * n_); }
  // "u_i" or "v_i" (i = 1..N) of the interleaved unknowns.
  std::string component_name(Index i) const override;

  int cells() const { return n_; }
  double alpha() const { return alpha_; }
  // c = α (N+1)², the coefficient of the second differences.
  double diffusion_coefficient() const { return c_; }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  int n_;
  double alpha_, c_;
};

}  // namespace stiffbench

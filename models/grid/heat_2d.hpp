// Heat2d: the heat equation u_t = ν Δu on the unit square, discretised in space by the 5-point
// stencil (method of lines), so the time integrators see the textbook stiff linear ODE
//   u_ij' = ν (u_{i+1,j} + u_{i-1,j} + u_{i,j+1} + u_{i,j-1} - 4 u_ij) / Δx².
// Grids (N = parameter n, unknowns N², index i + N j):
//   periodic   — cell centres x_i = (i + ½) Δx, Δx = 1/N, indices wrap;
//   dirichlet  — interior nodes x_i = (i + 1) Δx, Δx = 1/(N + 1), u = 0 on the boundary.
// The stencil's eigenvectors are the discrete Fourier (sine) modes with eigenvalues
//   periodic:  λ_kl = -(4ν/Δx²) [sin²(π k Δx) + sin²(π l Δx)],   mode sin(2πk x) sin(2πl y)
//   dirichlet: λ_kl = -(4ν/Δx²) [sin²(π k Δx/2) + sin²(π l Δx/2)], mode sin(kπ x) sin(lπ y)
// (from 2 cos θ - 2 = -4 sin²(θ/2)). The initial state is the mode (kx, ky) of amplitude 1, so the
// exact solution of the ODE is u(t) = e^{λ t} u(0): errors measure the time integrator alone
// (the continuous PDE decays at -ν(2π)²(k² + l²), resp. -νπ²(k² + l²); their difference is the
// O(Δx²) spatial error). Spectral radius (stiffness): the largest |λ_kl|, 8ν/Δx² for an even
// periodic N (the checkerboard mode), so explicit Euler is stable for h <= Δx²/(4ν) there; the
// suggested step is that limit (with the exact spectral radius: 2/ρ). The stiffness knob is ν/Δx².
// Jacobian: the constant sparse matrix of the stencil (ν/Δx² times the graph Laplacian).
#pragma once

#include <string>

#include "core/ode_system.hpp"

namespace stiffbench {

class Heat2d final : public OdeSystem {
 public:
  enum class Boundary { periodic, dirichlet };
  Heat2d(int n, double nu, Boundary boundary, int kx, int ky);

  std::string name() const override { return "heat_2d"; }
  Index dimension() const override { return static_cast<Index>(n_) * n_; }
  std::optional<double> end_time() const override;
  Vec initial_state() const override;
  bool autonomous() const override { return true; }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override;
  std::optional<double> stiffness(double, CVecRef) const override { return rho_; }
  std::optional<SuggestedStep> suggested_step() const override;

  int n() const { return n_; }
  double dx() const { return dx_; }
  double nu() const { return nu_; }
  Boundary boundary() const { return boundary_; }
  // Eigenvalue of the initial mode (the exact decay rate of the ODE).
  double mode_eigenvalue() const { return lambda_; }
  // Decay rate of the same mode for the continuous PDE.
  double continuous_eigenvalue() const;
  // Coordinate of grid index i along either axis.
  double coordinate(int i) const;

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  int n_;
  double nu_, dx_;
  Boundary boundary_;
  int kx_, ky_;
  double lambda_ = 0, rho_ = 0;
  Vec u0_;
};

}  // namespace stiffbench

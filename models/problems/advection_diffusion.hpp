// AdvectionDiffusion: the 1D periodic advection–diffusion–reaction equation
//   u_t + a u_x = ν u_xx - r u   on [0, 1),
// by the method of lines on N cells, x_j = j Δx, Δx = 1/N, central differences for both
// derivatives:
//   u_j' = -a (u_{j+1} - u_{j-1})/(2Δx) + ν (u_{j+1} - 2u_j + u_{j-1})/Δx² - r u_j   (indices mod
//   N).
// Initial state u_j = sin(2πk x_j) = sin(θ j), θ = 2πk/N.
//
// Exact solution of the ODE system (not of the PDE). The operator L is circulant, so its
// eigenvectors are e^{iθj}; applying it to one gives the eigenvalue
//   λ(θ) = -a (e^{iθ} - e^{-iθ})/(2Δx) + ν (e^{iθ} - 2 + e^{-iθ})/Δx² - r
//        = -i (a/Δx) sin θ - (4ν/Δx²) sin²(θ/2) - r  =  μ - iω,
// μ = -r - (4ν/Δx²) sin²(θ/2), ω = (a/Δx) sin θ. L is real and sin(θj) = Im e^{iθj}, so
//   u_j(t) = Im(e^{λt} e^{iθj}) = e^{μt} sin(θ j - ω t)
// (a travelling wave with the discrete phase speed ω/(2πk), decaying at rate -μ).
// stiffness(): the exact spectral radius max_m |λ(2πm/N)| (computed once over the N modes).
// Jacobian: the constant periodic tridiagonal matrix of L (3N entries; N >= 3).
//
// Additive split (split=advection, the only one): f_E = the advection term (explicit),
// f_I = diffusion and reaction (implicit), J_I their constant tridiagonal matrix.
// explicit_part_spectrum(): the central advection operator's eigenvalues are -i (a/Δx) sin θ_m,
// purely imaginary, of largest modulus (|a|/Δx) max_m |sin(2πm/N)| (= |a|/Δx for N divisible by
// 4): that radius on the imaginary axis.
// Parameters: n (N >= 3), a (any), nu (ν >= 0), r (>= 0), k (wave number >= 0). End time 1.
#pragma once

#include <string>

#include "core/ode_system.hpp"

namespace stiffbench {

class AdvectionDiffusion final : public OdeSystem {
 public:
  AdvectionDiffusion(int n, double a, double nu, double r, int k);

  std::string name() const override { return "advection_diffusion"; }
  Index dimension() const override { return n_; }
  std::optional<double> end_time() const override { return 1.0; }
  Vec initial_state() const override;
  bool autonomous() const override { return true; }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override;
  std::optional<double> stiffness(double, CVecRef) const override { return rho_; }

  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override;
  bool has_implicit_part_jacobian() const override { return true; }
  std::optional<SpectrumEstimate> explicit_part_spectrum(double, CVecRef) const override {
    return SpectrumEstimate{advection_radius_, SpectrumEstimate::Ray::imaginary};
  }

  double dx() const { return dx_; }
  // μ and ω of the exact solution (see the header comment).
  double decay_rate() const { return mu_; }
  double angular_frequency() const { return omega_; }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef fe) const override;
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const override;
  void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  // The periodic tridiagonal matrix with lower, diagonal and upper coefficients.
  void tridiagonal(double lower, double diag, double upper, SparseMat& jac) const;

  int n_;
  double a_, nu_, r_;
  int k_;
  double dx_, theta_, mu_, omega_, rho_, advection_radius_;
};

}  // namespace stiffbench

// Fully implicit Runge–Kutta methods from their tableau (ImplicitRungeKutta): any s-stage
// tableau whose A is invertible and whose A⁻¹ is diagonalisable, solved as one coupled
// simplified-Newton system. Built in: Gauss–Legendre collocation with s = 2 (gauss4, order 4)
// and s = 3 (gauss6, order 6): implicit, A-stable with |R(iy)| = 1 (R is the diagonal Padé
// approximant of e^z), symplectic and symmetric (Hairer, Lubich & Wanner, Geometric Numerical
// Integration, §II.1.3, §VI.4; Butcher 1964). Method files of kind "irk" (Radau IIA, Lobatto
// IIIC, a user's own; integrators/method_file.hpp) run on the same class. Fixed step.
//
// Gauss tableaux (methods/gauss4.toml, gauss6.toml; Hairer–Nørsett–Wanner I, §II.7; c the zeros
// of the shifted Legendre polynomial):
//   s = 2: c = ½ ∓ √3/6,  A = [[¼, ¼ - √3/6], [¼ + √3/6, ¼]],  b = (½, ½)
//   s = 3: c = ½ - √15/10, ½, ½ + √15/10, b = (5/18, 4/9, 5/18),
//          A = [[5/36, 2/9 - √15/15, 5/36 - √15/30],
//               [5/36 + √15/24, 2/9, 5/36 - √15/24],
//               [5/36 + √15/30, 2/9 + √15/15, 5/36]]
//
// Stage equations for Z_i = Y_i - y_n:  Z = h (A ⊗ I) F(Z),  y_{n+1} = y_n + Σ_j d_j Z_j with
// dᵀ = bᵀA⁻¹ (equal to y_n + h Σ b_i f(Y_i) at the solution; no further f evaluations, HW II
// IV.8). Simplified Newton with J = ∂f/∂y at (t_n, y_n): instead of the Kronecker system
// (I - hA ⊗ J) ΔZ = -G of size s·n, the variables W = (T⁻¹ ⊗ I) Z with T⁻¹ A⁻¹ T = Λ
// block-diagonal (real 1×1 blocks γ for real eigenvalues of A⁻¹, 2×2 blocks [[a, b], [-b, a]]
// for pairs a ± ib; T from A⁻¹'s eigenvectors, computed from the tableau at construction)
// give independent systems
//   (γ/h I - J) ΔW_j = r_j              (real eigenvalue)
//   ((a - ib)/h I - J)(ΔW_j + iΔW_{j+1}) = r_j + i r_{j+1}   (complex pair)
// with r = (T⁻¹ ⊗ I) F - h⁻¹ (Λ ⊗ I) W, the transformation of radau5 (HW II §IV.8). Gauss4's
// A⁻¹ has one complex pair (one complex n×n system per iteration), gauss6's one real
// eigenvalue and one pair (one real and one complex system). The linear solvers are radau5's
// ShiftedSolver: dense LU where automatic_is_dense says so or with linear_solver=dense_lu,
// SparseRefactorLu over the pattern of J otherwise or with linear_solver=sparse_lu.
//
// The tableau is checked at construction (BadInput naming it): ButcherTableau::validate (sizes,
// c = row sums, the claimed order); A invertible (smallest singular value above 1e-12 of the
// largest); A⁻¹ diagonalisable to round-off by the real basis T: a repeated eigenvalue without a
// full set of eigenvectors (e.g. an SDIRK's A, whose A⁻¹ is one Jordan block) would make the
// block-diagonal Λ, and so the method actually solved, differ from the tableau, so the
// reconstruction T Λ⁻¹ T⁻¹ must equal A to 1e-12 (relative to max |a_ij|, at least 1).
//
// Newton: starting values from the previous step's stage polynomial when the step continues
// the last one (zero otherwise). When no node is 0, q(σ) (σ = (t - t_{n-1})/h_prev) is the
// polynomial through q(0) = 0 and q(c_j) = Z_j^prev (a collocation method's collocation
// polynomial), continued to the new nodes: Z_i = q(1 + c_i h/h_prev) - q(1). When a node is 0
// (Lobatto), q interpolates the s stage values (c_j, Z_j^prev) only and Z_i = q(1 + c_i h/h_prev)
// - Σ_j d_j Z_j^prev. When the nodes are not distinct, zero. θ_k = ‖ΔW_k‖/‖ΔW_{k-1}‖, RMS norm
// scaled by 1 + |y_n,i|, and the stopping test of every implicit method (integrators/solvers/
// newton.hpp): converged when θ_k/(1 - θ_k) ‖ΔW_k‖ ≤ newton_tol, or ‖ΔW_k‖ at round-off
// (4ε; 100ε once contraction has stopped); diverging when θ_k ≥ 1 above that; too slow when
// θ_k^(newton_max_iter - k)/(1 - θ_k) ‖ΔW_k‖ > newton_tol. The default newton_tol = 1e-15
// iterates to round-off, so that the step is the (for Gauss: symplectic) map itself and the
// energy error of long Gauss runs stays bounded without drift (GNI §VIII.6); a looser tolerance
// adds a non-symplectic perturbation of that size each step. A failure (diverging, too slow,
// non-finite values, newton_max_iter iterations) ends the run with newton_failed and the reason
// and θ in the message.
//
// Counting: s f evaluations per Newton iteration; linear_setups +1 per factorisation (real or
// complex), lin_solves +1 per system solved; J at every step (analytic, or finite differences
// through the shared ImplicitCore, always the first-order form of mechanical systems). The
// dense and the sparse path allocate nothing in a step after the first.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "core/integrator.hpp"
#include "core/theory/tableau.hpp"
#include "integrators/implicit/radau5.hpp"
#include "integrators/solvers/newton.hpp"

namespace stiffbench {

// s = 2 or 3: the tableaux of the method files gauss4 and gauss6 (methods/*.toml).
const ButcherTableau& gauss_tableau(int stages);

struct GaussOptions {
  double newton_tol = 1e-15;
  int newton_max_iter = 20;
  JacobianSource jacobian = JacobianSource::automatic;
  LinearSolverKind linear = LinearSolverKind::automatic;
};

std::vector<ParamSpec> gauss_param_specs();
GaussOptions read_gauss_options(const Params& p);

// The transformation of the Newton iteration (exposed for the tests): T⁻¹ A⁻¹ T = Λ with the
// real eigenvalues first, then one 2×2 block [[a, b], [-b, a]] per complex pair.
struct IrkConstants {
  Mat t, t_inv, lambda;
  std::vector<double> real;  // real eigenvalues of A⁻¹ (Λ's leading 1×1 blocks)
  std::vector<double> a, b;  // complex pairs a ± ib (Λ's 2×2 blocks)
  Vec d;                     // dᵀ = bᵀ A⁻¹
};
using GaussConstants = IrkConstants;

// The constants of `tableau` (its A must be s×s); BadInput naming the tableau when A is
// singular or A⁻¹ is not diagonalisable to round-off (see above).
IrkConstants irk_constants(const ButcherTableau& tableau);
const GaussConstants& gauss_constants(int stages);

class ImplicitRungeKutta final : public Integrator {
 public:
  // BadInput naming the tableau when it fails its checks (see above). MethodInfo: the
  // tableau's name and order, family implicit, s stages, `description` (kind and reference
  // come with the registration).
  ImplicitRungeKutta(ButcherTableau tableau, std::string description, GaussOptions opt);

  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  void restart(const OdeSystem& sys, double t, CVecRef y) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return tableau_stability(tableau_);
  }
  const ButcherTableau* butcher_tableau() const override { return &tableau_; }
  const IrkConstants& constants() const { return k_; }

 private:
  void restart_state();  // what reset() and restart() clear
  NewtonAttempt solve_stages(const OdeSystem& sys, double t, CVecRef y, double h,
                             SolveStats& stats);
  void starting_values(double h);

  ButcherTableau tableau_;
  IrkConstants k_;
  int s_;
  // Starting values: interpolate the last step's stages (distinct nodes), with q(0) = 0 unless
  // a node is 0.
  bool interpolate_ = false, zero_node_ = false;
  GaussOptions opt_;
  ImplicitCore core_;
  std::vector<ShiftedSolver<double>> real_;
  std::vector<ShiftedSolver<std::complex<double>>> complex_;
  Index n_ = 0;
  Mat z_, w_, f_, z_prev_;
  Vec f0_, scale_, tmp_, r1_, x1_;
  Eigen::VectorXcd r2_, x2_;
  double h_prev_ = 0.0;
  bool have_prev_ = false;
  const double* cached_y_ = nullptr;
  double cached_t_ = 0.0;
};

}  // namespace stiffbench

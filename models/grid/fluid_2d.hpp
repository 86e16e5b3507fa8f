// Fluid2d: incompressible Navier–Stokes on the unit square [0, 1]², a staggered (MAC) grid of
// N × N square cells (Δx = 1/N), written as an ODE on discretely divergence-free velocity fields
//   u' = P[-(u·∇)u + νΔu + g],
// P the discrete pressure projection (so every Runge–Kutta stage, a linear combination of
// divergence-free fields, stays divergence-free; pressure is not a state variable).
//
// Grid (Harlow & Welch 1965): u_ij at the vertical faces (iΔx, (j + ½)Δx), v_ij at the horizontal
// faces ((i + ½)Δx, jΔx), pressure at the cell centres. State y = [u; v], u index i + N_u j with
// N_u faces per row, then v index i + N j.
//   periodic  (Taylor–Green): N_u = N, v rows j ∈ [0, N); indices wrap.
//   walls     (cavity): the boundary faces are stored and stay 0 (u at i = 0, N; v at j = 0, N):
//             no penetration; no slip through ghost values across a wall at distance Δx/2:
//             u(i, -1) = -u(i, 0), u(i, N) = 2U - u(i, N-1) (the lid y = 1 moves at U along x),
//             v(-1, j) = -v(0, j), v(N, j) = -v(N-1, j) (deeper ghosts reflect likewise).
// Discrete operators (second order, on the free faces):
//   divergence (Du)_ij = (u_{i+1,j} - u_ij + v_{i,j+1} - v_ij)/Δx, gradient (Gp) = -Dᵀp (so
//   the boundary faces get no pressure gradient: Neumann), pressure Laplacian DG = -DDᵀ: the
//   5-point stencil with Neumann walls;
//   viscous term νL u + νb: the 5-point stencil on each component with the ghost values above
//   (b carries the lid's 2U/Δx²);
//   advection (u·∇)u in advective form with central differences, v̄ (ū) the average of the four
//   v (u) values around a u (v) face.
// Projection: P F = F - Dᵀψ with DDᵀψ = DF; DDᵀ is singular (constants), so ψ_0 = 0 is pinned
// (row and column 0 replaced by the identity; the equation dropped is implied by the others,
// since ΣDF = 0 on both grids). Factorised once per grid by Eigen's SimplicialLDLT (parameter
// solver=cholesky) or solved by conjugate gradients (solver=cg, warm-started, relative 1e-12).
// Pressure (per unit density): p = -ψ, the field with P F = F - Gp.
//
// Scenes:
//   taylor_green — periodic, u = sin 2πx cos 2πy, v = -cos 2πx sin 2πy (divergence-free on the
//     MAC grid exactly: the differences of the sines give the same cos·cos factor), ν = 1/Re.
//     The PDE's kinetic energy decays as E(t) = E(0) e^{-16π²νt} (Taylor & Green 1937: the field is
//     the |k|² = 8π² eigenmode and the advection term is a pure gradient).
//   cavity — lid-driven cavity, walls, lid speed 1 at y = 1, ν = 1/Re, starting at rest
//     (Ghia, Ghia & Shin 1982 for the steady centreline profiles).
// Kinetic energy E = ½ Σ (u² + v²) Δx² over the faces (per unit density).
// Suggested step: min(Δx²/(4ν), Δx/U) — explicit Euler's diffusion limit on the checkerboard
// mode (8ν/Δx²) and a unit Courant number for the largest speed U (lid speed, or max |u0|).
// stiffness(): 8ν/Δx² + 2U/Δx (diffusion's largest eigenvalue plus a bound of the central
// advection operator's), a rough scale. No analytic Jacobian (P makes it dense): implicit
// methods use finite differences or matrix-free Krylov products.
//
// Additive split (parameter split=diffusion; default none, no split and f bitwise unchanged):
//   f_E = P[-(u·∇)u + g]   advection and gravity (explicit),
//   f_I = P[νL u + νb]     diffusion with the lid's boundary term (implicit).
// The projection stays as it is, applied to each part: P is linear, so f_E + f_I = f up to the
// rounding of the two projections (ΣDF = 0 holds for each part alone, so the pinned Poisson
// equation is consistent for both). No analytic J_I = νPL (P makes it dense, like J): the IMEX
// methods' implicit stages use finite-difference Jacobians of f_I (dense, up to 200 unknowns) or
// matrix-free Krylov products (above), ARKODE dense difference quotients or SPGMR likewise. On
// the periodic grid L commutes with D and Dᵀ, so on divergence-free fields f_I = νLu exactly
// (Taylor–Green's field is an eigenfunction of L, f_I = νλ_h u with λ_h = -(8/Δx²) sin²(πΔx), and
// its central advection term is a discrete gradient, so f_E = 0 on it: the semi-discrete solution
// is e^{νλ_h t} u0, derived in tests/models/test_fluid_split.cpp).
// explicit_part_spectrum(): the Jacobian of the central advection at the state U,
// -(U·∇)δu - (δu·∇)U, is skew-symmetric to leading order: its transport part has the local
// symbol -i(u sin θ_x + v̄ sin θ_y)/Δx at a u face (u its own velocity, v̄ the average of the four
// v around it; likewise at a v face), so its eigenvalues lie near the imaginary axis with modulus
// up to about (|u| + |v̄|)/Δx. The estimate is the largest (|u| + |v̄|)/Δx over the free faces,
// on the imaginary ray: at most 2U/Δx (U the largest velocity component), about 1/Δx for the
// Taylor–Green field (|u| + |v| = |sin(2πx ± 2πy)| ≤ 1). The lower-order -(δu·∇)U moves the
// eigenvalues off the axis by O(|∇U|). Against the dense eigenvalues of ∂f_E/∂y (P included) on
// 12 × 12 grids it lies 1.3-1.7 times above the largest modulus, tending to 1 on finer grids for a
// smooth field (tests/models/test_fluid_split.cpp).
//
// GridFluid operators (for stable_fluids, Stam 1999):
//   advect — departure point x - h u(x) traced by the midpoint rule (velocity sampled at x and at
//     x - ½h u(x)), clamped into the box; the transported component interpolated there
//     bilinearly (advection=linear, Stam's choice) or by Catmull–Rom cubics (advection=cubic).
//     Linear interpolation is first-order upwind in disguise: for small Courant numbers it adds a
//     numerical viscosity of about |u|Δx/2, whatever h is; cubic interpolation's error is O(Δx⁴)
//     per step (numerical diffusion O(|u|Δx³)).
//   diffuse — backward Euler (I - hνL) out = in + hνb, SimplicialLDLT refactorised when h
//     changes;
//   project_divergence_free — the projection above applied to the state.
#pragma once

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <memory>
#include <string>
#include <vector>

#include "core/grid_fluid.hpp"
#include "core/ode_system.hpp"

namespace stiffbench {

struct Fluid2dOptions {
  enum class Scene { taylor_green, cavity } scene = Scene::taylor_green;
  int n = 32;          // cells per direction
  double re = 100;     // Reynolds number UL/ν with U = 1, L = 1: ν = 1/Re
  double lid = 1.0;    // cavity lid speed U
  double gravity = 0;  // along -y
  enum class Solver { cholesky, cg } solver = Solver::cholesky;
  enum class Advection { linear, cubic } advection = Advection::linear;
  enum class Split { none, diffusion } split = Split::none;
};

class Fluid2d final : public OdeSystem, public GridFluid {
 public:
  explicit Fluid2d(const Fluid2dOptions& options);

  std::string name() const override { return "fluid_2d"; }
  Index dimension() const override { return nu_count_ + nv_count_; }
  Vec initial_state() const override { return y0_; }
  // taylor_green: Re/(16π²), one e-fold of the PDE's kinetic energy; cavity: none (give --t-end;
  // the 64 x 64 Re = 100 cavity is steady to 1e-7 in kinetic energy by t = 30).
  std::optional<double> end_time() const override;
  bool autonomous() const override { return true; }
  std::optional<double> stiffness(double, CVecRef) const override;
  std::optional<SuggestedStep> suggested_step() const override;
  std::vector<Invariant> observables() const override;
  bool has_grid() const override { return true; }
  GridFrame grid_frame(double t, CVecRef y) const override;
  // cavity: "centreline" (columns y, u: centreline_u).
  std::vector<Profile> profiles(double t, CVecRef y) const override;
  const GridFluid* as_grid_fluid() const override { return this; }

  // Additive split (split=diffusion; see the header comment).
  bool has_imex_split() const override { return opt_.split == Fluid2dOptions::Split::diffusion; }
  std::optional<SplitInfo> imex_split() const override;
  std::optional<SpectrumEstimate> explicit_part_spectrum(double t, CVecRef y) const override;

  // GridFluid (see the header comment).
  void add_body_force(double h, VecRef y) const override;
  void advect(double h, CVecRef vel, CVecRef q, VecRef out) const override;
  int diffuse(double h, CVecRef in, VecRef out) const override;
  int project_divergence_free(VecRef y) const override;

  // Data and observables.
  const Fluid2dOptions& options() const { return opt_; }
  int n() const { return n_; }
  double dx() const { return dx_; }
  double nu() const { return nu_; }
  bool periodic() const { return periodic_; }
  double kinetic_energy(CVecRef y) const;
  Vec divergence(CVecRef y) const;  // (Dy)_ij per cell, i fastest
  double max_divergence(CVecRef y) const;
  // Pressure (per unit density) of the projection of f at y: the p with f = F - Gp.
  Vec pressure(CVecRef y) const;
  // Vorticity ∂v/∂x - ∂u/∂y at the cell centres (averaged from the cell corners).
  Vec vorticity(CVecRef y) const;
  // Velocity interpolated to the cell centres (u then v per cell).
  void cell_velocity(CVecRef y, Vec& uc, Vec& vc) const;
  // u-velocity on the vertical centreline x = 0.5 at the cell-centre heights y_j = (j + ½)Δx
  // (n even: the faces i = n/2; odd: the mean of the two faces around x = 0.5).
  std::vector<std::pair<double, double>> centreline_u(CVecRef y) const;
  // 1 on the free faces, 0 on the fixed boundary faces (cavity).
  const Vec& free_faces() const { return free_; }
  // The pressure Poisson matrix DDᵀ with cell 0 pinned (tests).
  const SparseMat& poisson_matrix() const { return poisson_; }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef fe) const override;
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const override;

 private:
  // -(u·∇)u - g on the free faces, 0 on the fixed ones (the unprojected advection and gravity).
  void advection_terms(CVecRef y, VecRef f) const;
  // f -= Dᵀψ with DDᵀψ = Df (the projection of f in place); psi the warm start and result.
  void project_in_place(VecRef f, Vec& psi) const;
  // A velocity value at integer face indices, any (i, j): the stored entry k (< 0: none) times
  // s, plus c (ghosts across walls, periodic wrap; see the header comment).
  struct Ref {
    Index k = -1;
    double s = 0, c = 0;
  };
  Ref u_ref(int i, int j) const;
  Ref v_ref(int i, int j) const;
  double u_at(const double* y, int i, int j) const;
  double v_at(const double* y, int i, int j) const;
  Index u_index(int i, int j) const { return i + static_cast<Index>(nux_) * j; }
  Index v_index(int i, int j) const { return nu_count_ + i + static_cast<Index>(n_) * j; }
  // Interpolated component (u: comp 0, v: comp 1) of field y at the point (x, y).
  double sample(const double* y, int comp, double px, double py) const;
  void solve_pressure(CVecRef div, Vec& psi) const;
  void build_operators();

  Fluid2dOptions opt_;
  int n_ = 0, nux_ = 0, nvy_ = 0;
  Index nu_count_ = 0, nv_count_ = 0;
  double dx_ = 0, nu_ = 0, speed_ = 0;
  bool periodic_ = true;
  Vec y0_;
  Vec free_;           // 1 on free faces, 0 on the fixed boundary faces
  SparseMat lap_;      // L (free faces only)
  Vec lap_const_;      // b
  SparseMat div_;      // D: cells × faces (free faces only)
  SparseMat div_t_;    // Dᵀ
  SparseMat poisson_;  // DDᵀ, cell 0 pinned
  Eigen::SimplicialLDLT<SparseMat> chol_;
  mutable Eigen::ConjugateGradient<SparseMat, Eigen::Lower | Eigen::Upper> cg_;
  // Scratch of one evaluation (allocated once).
  mutable Vec rhs_div_, psi_;
  // The projections' ψ of the split's parts (kept apart from psi_, which pressure() reads and the
  // full f warm-starts CG with).
  mutable Vec psi_e_, psi_i_;
  // Implicit diffusion matrix I - hνL, factorised for step last_h_.
  mutable Eigen::SimplicialLDLT<SparseMat> diff_chol_;
  mutable double last_h_ = -1;
  mutable Vec diff_rhs_;
};

}  // namespace stiffbench

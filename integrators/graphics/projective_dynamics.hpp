// Projective dynamics for mass-spring networks: Liu, Bargteil, O'Brien & Kavan, "Fast simulation
// of mass-spring systems" (SIGGRAPH Asia 2013). It needs the system's springs (core/springs.hpp)
// and refuses other systems (check_compatible names the model).
//
// The step is backward Euler, x⁺ = x + h v⁺, M (v⁺ - v) = h (f_s(x⁺) + M g - γ v⁺), written as a
// minimisation over x⁺ (Liu et al. Eq. 2; the point damping -γv is linear in x⁺ and joins the
// mass matrix, M̃ = M + hγI):
//   x⁺ = argmin ½ (x - s)ᵀ M̃ (x - s) + h² Σ_springs ½ k (|x_j - x_i| - L)²,
//   M̃ s = M (x + h v + h² g) + hγ x,
// with each spring energy written as min over |d| = L of ½ k |x_j - x_i - d|² (their Eq. 8).
// `iterations` alternations of
//   local:  d = L (x_j - x_i)/|x_j - x_i| for every spring (projection onto the rest length;
//           d = 0 when the ends coincide);
//   global: (M̃ + h² L) x = M̃ s + h² J d, L = Σ k (e_j - e_i)(e_j - e_i)ᵀ (the spring graph's
//           weighted Laplacian on free points), one scalar system per coordinate;
// starting from x = s. The matrix M̃ + h² L is constant: it is factorised (sparse LDLᵀ with AMD
// ordering, integrators/solvers/linear_solver.hpp) once per (system, h) and reused by every
// iteration of every step. Pinned points have infinite mass: they are not unknowns, and springs
// to them move their positions to the right-hand side. Each iteration does not increase the
// objective (block coordinate descent, Liu et al. §4), and the fixed point is the backward-Euler
// step, so the method converges to backward Euler (order 1) as iterations grow; after a fixed
// count it is an approximation of it whose error the tests measure.
// Dashpots (spring damping c > 0) are not modelled by the method (it minimises the spring
// potential only): networks with them are refused with BadInput. Point damping is exact.
// Distance constraints of the model are enforced by the driver's projection, as for every
// integrator. Cost per step: `iterations` × (one pass over the springs + dim triangular solve
// pairs); no f evaluations (f_evals stays 0: compare cost by wall time). Counted in the stats:
// linear_setups (factorisations), lin_solves (dim per iteration).
#pragma once

#include <memory>
#include <vector>

#include "core/integrator.hpp"
#include "core/params.hpp"
#include "core/springs.hpp"
#include "integrators/solvers/linear_solver.hpp"

namespace stiffbench {

struct ProjectiveDynamicsOptions {
  int iterations = 10;
};

std::vector<ParamSpec> projective_dynamics_param_specs();
ProjectiveDynamicsOptions read_projective_dynamics_options(const Params& p);

class ProjectiveDynamics final : public Integrator {
 public:
  explicit ProjectiveDynamics(ProjectiveDynamicsOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;

 private:
  struct Link {
    Index i, j;    // point indices
    Index ri, rj;  // rows of the free points (-1: pinned)
    double rest, k;
  };
  bool factor(double h);

  ProjectiveDynamicsOptions opt_;
  const OdeSystem* sys_ = nullptr;
  const SpringNetworkView* net_ = nullptr;
  std::vector<Link> links_;
  std::vector<Index> row_of_;     // per point: its row, or -1 when pinned
  std::vector<Index> point_of_;   // per row: its point
  SparseMat laplacian_, matrix_;  // L and M̃ + h² L (same pattern, diagonal stored)
  std::vector<Index> diag_pos_;   // per row: its diagonal entry in valuePtr()
  std::unique_ptr<LinearSolver> solver_;
  double factored_h_ = 0.0;  // 0: not factored
  Mat base_rhs_, rhs_, x_;   // rows × dim: M̃ s, the global right-hand side, the iterate
};

}  // namespace stiffbench

// The linear systems W k = r, W = I - c J, of the implicit methods on a MechanicalSystem, whose
// first-order Jacobian is J = [[0, I], [K, D]] (K = ∂a/∂x, D = ∂a/∂v), solved in velocity form.
// Eliminating k_x from
//   k_x - c k_v = r_x,        k_v - c (K k_x + D k_v) = r_v
// leaves a system of the dofs' size n (half of 2n):
//   A k_v = M (r_v + c K r_x),   A = M - c M D - c² M K,   then k_x = r_x + c k_v.
// The elimination is exact: Newton iterates equal those of the first-order form up to round-off
// and the linear solver's tolerance (tests/integrators/test_velocity_form.cpp compares the two
// forms). Scaling the rows by the diagonal mass matrix M makes A symmetric when M K and M D are
// (MechanicalSystem::symmetric_force_jacobians()), and positive definite where -M K and -M D
// are positive semi-definite (mass-spring networks with the `compressed_dd_only` option).
//
// Fixed dofs (MechanicalSystem::fixed_dofs(): pinned points, whose rows of K and D are zero)
// satisfy k_v,f = r_v,f exactly. They are eliminated as in Baraff & Witkin's filtered CG: row and
// column f of A keep only the diagonal M_ff, and the column's entries move to the right-hand
// side. With pins A therefore stays symmetric, which CG and LDLT need.
//
// Linear solver (`linear_solver`, resolved by reset() when `auto`): symmetric A → ldlt up to
// kVelocityLdltMax dofs, cg with a Jacobi preconditioner above (a cg that meets non-positive
// curvature, possible when compressed springs make K indefinite, switches the run to ldlt);
// non-symmetric A (dashpots) → dense_lu up to 200 dofs, sparse_lu above.
//
// Assembly: A's pattern (K's, D's and the diagonal) and the position in it of every entry of K
// and D are computed once; each factor() writes A's values in place (in parallel over columns
// for large systems), so a step allocates nothing. When A is symmetric and made of dense 2×2 or
// 3×3 blocks (mass-spring networks in 2D and 3D), Krylov solvers multiply with a block-row copy
// of A (one index per block instead of one per entry, rows in parallel): the product is the
// Krylov solvers' main cost.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/ode_system.hpp"
#include "integrators/solvers/linear_solver.hpp"

namespace stiffbench {

constexpr Index kVelocityLdltMax = 2000;

// The solver `auto` picks for the velocity-form matrix of n dofs (see the header comment).
LinearSolverKind velocity_form_auto_solver(Index n, bool symmetric);

class VelocityFormSolver {
 public:
  // Patterns, maps and the linear solver for `sys`; K and D evaluated at (t0, y0).
  void reset(const MechanicalSystem& sys, LinearSolverOptions opt, double t0, CVecRef y0);
  // K and D at (t, y) = (t, [x; v]), in place.
  void update(double t, CVecRef y);
  // A for W = I - c J with the current K and D, factored (direct) or set up (Krylov).
  bool factor(double c);
  // Solves W k = r (both of size 2n); k's velocity half is the Krylov initial guess.
  LinearSolveResult solve(CVecRef r, VecRef k);
  // out = J u (size 2n) with the current K and D.
  void jacobian_times(CVecRef u, VecRef out) const;

  void set_tolerance(double tol) { solver_->set_tolerance(tol); }
  const std::string& error() const { return error_; }
  LinearSolverKind kind() const { return solver_->kind(); }
  bool symmetric() const { return opt_.symmetric; }
  Index dofs() const { return n_; }
  const SparseMat& matrix() const { return a_; }
  // Block size of the block-row copy used for Krylov products (0: none).
  int block_size() const { return block_; }

 private:
  void make_solver(LinearSolverKind kind);
  // A's pattern and the maps from the current K and D (at reset, and again if a model's blocks
  // change their pattern, as small models that rebuild them do).
  void build_pattern();
  bool same_patterns() const;

  const MechanicalSystem* sys_ = nullptr;
  LinearSolverOptions opt_;
  bool auto_kind_ = false;
  bool velocity_dependent_ = true;
  Index n_ = 0;
  double c_ = 0.0;
  Vec m_;
  SparseMat k_, d_, a_;
  std::vector<int> k_outer_, k_inner_, d_outer_, d_inner_;  // patterns seen by build_pattern()
  std::vector<int> k_map_, d_map_;  // position in a_ of every entry of k_ / d_
  std::vector<int> diag_pos_;       // position in a_ of each diagonal entry
  std::vector<Index> fixed_;        // fixed dofs
  std::vector<char> is_fixed_;
  std::vector<int> fixed_entries_;  // off-diagonal entries of a_ in a fixed row or column
  struct Coupling {
    int pos;      // entry of a_ in a fixed column and a free row
    Index row;    // that free row
    Index fixed;  // that fixed column
  };
  std::vector<Coupling> couplings_;
  Vec coupling_values_;  // their values in the last factor()
  std::unique_ptr<LinearSolver> solver_;
  std::string error_;
  // Block-row (BSR) copy of a symmetric A: block row I holds columns bI..bI+b-1 of A (its rows,
  // by symmetry); bsr_pos_[k] is where entry k of a_ goes.
  void detect_blocks();
  // out = M K r (symmetric M K: column i of K gives row i of M K, in parallel; the entries of
  // fixed columns at free rows, where the symmetry of the stored K breaks, added separately).
  void mk_product(CVecRef r, VecRef out) const;
  struct FixedColumnEntry {
    int k;        // entry of k_
    Index row;    // free row
    Index fixed;  // fixed column
  };
  std::vector<FixedColumnEntry> k_fixed_cols_;
  void block_product(CVecRef in, VecRef out) const;
  int block_ = 0;
  std::vector<int> bsr_row_, bsr_col_, bsr_pos_;
  std::vector<double> bsr_val_;
  Vec rhs_, kv_;
};

}  // namespace stiffbench

// Linear solvers for the Newton and linearly implicit systems W x = b of the implicit methods,
// where W has a sparsity pattern that is fixed for a run. Direct solvers analyse the pattern
// once (analyze) and refactor only numerically (factor); Krylov solvers run on an assembled
// matrix or on a matrix-free operator (a Jacobian-vector product).
//
//   dense_lu   Eigen PartialPivLU on the dense copy (small systems)
//   sparse_lu  Eigen SparseLU (COLAMD ordering), symbolic analysis reused across steps
//   ldlt       Eigen SimplicialLDLT (AMD ordering): symmetric matrices only
//   cg         preconditioned conjugate gradients: symmetric positive definite matrices only
//   bicgstab   preconditioned BiCGSTAB (van der Vorst 1992)
//   gmres      restarted GMRES(m) with right preconditioning (Saad & Schultz 1986)
// Preconditioners for the Krylov solvers: none, jacobi (diagonal of W).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace stiffbench {

enum class LinearSolverKind { automatic, dense_lu, sparse_lu, ldlt, cg, bicgstab, gmres };
enum class PreconditionerKind { none, jacobi };

LinearSolverKind parse_linear_solver(const std::string& s);
std::string to_string(LinearSolverKind k);
bool is_krylov(LinearSolverKind k);
const std::vector<std::string>& linear_solver_names();

struct LinearSolverOptions {
  LinearSolverKind kind = LinearSolverKind::automatic;
  PreconditionerKind preconditioner = PreconditionerKind::jacobi;
  double krylov_tol = 1e-12;  // relative residual ‖b - Wx‖ ≤ tol ‖b‖
  int krylov_max_iter = 1000;
  int gmres_restart = 50;
  Index dense_max = 200;  // `automatic` picks dense_lu up to this dimension, sparse_lu above
};

// y = W x for the matrix-free path.
using LinearOperator = std::function<void(CVecRef x, VecRef y)>;

struct LinearSolveResult {
  bool ok = true;
  long iterations = 0;  // Krylov iterations (0 for direct solvers)
  double residual = 0;  // final relative residual (Krylov)
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  // The pattern of every matrix later passed to factor(); symbolic work happens here, once.
  virtual void analyze(const SparseMat& pattern) = 0;
  // Numeric set-up for W (same pattern as analyze). False if W is singular.
  virtual bool factor(const SparseMat& w) = 0;
  // Solves W x = b with the last factored W; x holds the initial guess for Krylov solvers.
  virtual LinearSolveResult solve(CVecRef b, VecRef x) = 0;
  virtual LinearSolverKind kind() const = 0;
};

// `automatic` is resolved with n and options.dense_max.
std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& opt, Index n);

// Krylov iterations on an operator (assembled or matrix-free). `diag` is the Jacobi
// preconditioner's diagonal of W (empty: no preconditioner).
LinearSolveResult krylov_solve(LinearSolverKind kind, const LinearOperator& op, const Vec& diag,
                               CVecRef b, VecRef x, const LinearSolverOptions& opt);

}  // namespace stiffbench

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
// Preconditioners for the Krylov solvers: none, jacobi (diagonal of W), ichol (Eigen's
// incomplete Cholesky with AMD ordering, cg only).
//
// Solver objects keep their work vectors between solves (no allocation per solve after the first
// of a given size). A solver that cannot take a matrix (ldlt or cg given a non-symmetric one, cg
// meeting a direction of non-positive curvature, a singular factorisation) returns false and says
// why in error(), so callers report a linear-solver failure, not a Newton failure.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace stiffbench {

enum class LinearSolverKind { automatic, dense_lu, sparse_lu, ldlt, cg, bicgstab, gmres };
enum class PreconditionerKind { none, jacobi, ichol };

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
  // `automatic` picks dense_lu up to dense_max unknowns and sparse_lu above, and sparse_lu from
  // dense_small on when W's pattern is known to fill under kSparsePatternDensity of the matrix:
  // a banded 200 x 200 system (the Brusselator with diffusion, n = 100) factorises in
  // microseconds sparse and in 2-20 ms dense (complex: radau5), 60 times the run's time.
  Index dense_max = 200;
  Index dense_small = 50;
  double pattern_density = 1.0;  // nonzeros / n² of W's pattern (1: unknown or dense)
  // The caller knows W is symmetric (e.g. the velocity-form matrix of a model with symmetric
  // force Jacobians): ldlt and cg skip their O(nnz) symmetry check, and products with W run in
  // parallel (OpenMP) row by row on the column-major storage.
  bool symmetric = false;
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
  // Relative residual target of later Krylov solves (Eisenstat–Walker forcing); no effect on
  // direct solvers.
  virtual void set_tolerance(double) {}
  // Krylov solvers: apply W through `product` (e.g. a block-sparse copy of W) instead of the
  // matrix passed to factor(), which still supplies the preconditioner. Set once per run.
  virtual void use_product(LinearOperator) {}
  // Why the last factor() or solve() failed.
  const std::string& error() const { return error_; }

 protected:
  std::string error_;
};

constexpr double kSparsePatternDensity = 0.1;

// Whether `automatic` resolves to dense_lu for n unknowns (see LinearSolverOptions::dense_max).
bool automatic_is_dense(const LinearSolverOptions& opt, Index n);

// `automatic` is resolved by automatic_is_dense.
std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& opt, Index n);

// Work vectors of the Krylov methods, kept by their owner across solves.
struct KrylovWorkspace {
  Vec r, r0, z, p, v, s, t, ph, sh, w, cs, sn, g, y, update;
  Mat basis, hess;
};

// Krylov iterations on an operator (assembled or matrix-free). `diag` is the Jacobi
// preconditioner's diagonal of W (empty: no preconditioner).
LinearSolveResult krylov_solve(LinearSolverKind kind, const LinearOperator& op, const Vec& diag,
                               CVecRef b, VecRef x, const LinearSolverOptions& opt,
                               KrylovWorkspace& ws);

// out = W in for a symmetric W in compressed column-major storage, computed row by row (row i of
// W is its column i) over OpenMP threads when W is large; each entry is summed in a fixed order,
// so the result does not depend on the thread count.
void symmetric_product(const SparseMat& w, CVecRef in, VecRef out);

}  // namespace stiffbench

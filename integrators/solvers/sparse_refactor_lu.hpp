// Sparse LU with one symbolic analysis per pattern and numeric refactorisation without
// allocation, for the shifted systems (shift·I - J) of radau5 and the implicit Runge–Kutta
// methods on their sparse path (linear_solver=sparse_lu), real or complex.
//
//   analyze(A)  COLAMD column ordering of A's pattern (Eigen's COLAMDOrdering, the one of
//               Eigen::SparseLU); the pattern is kept.
//   factor(A)   the first time (and whenever a pivot of the numeric refactorisation gets too
//               small): a left-looking LU with threshold partial pivoting (Gilbert & Peierls,
//               "Sparse partial pivoting in time proportional to arithmetic operations", 1988;
//               the algorithm of Davis, Direct Methods for Sparse Linear Systems, 2006, cs_lu):
//               column k of P A Q is a sparse triangular solve with the columns of L found so
//               far, over the depth-first reach of A(:, q_k) in the graph of L; the pivot is the
//               diagonal entry when it is at least `diag_tol` (0.1) of the largest candidate, the
//               largest otherwise. That fixes the row permutation and the patterns of L and U.
//               Later calls with the same pattern replay the same elimination numerically into
//               the same storage (KLU's "refactor", Davis & Palamadai Natarajan, "Algorithm 907:
//               KLU", ACM TOMS 37, 2010): no search, no allocation. A refactorised pivot smaller
//               than `refactor_tol` (1e-3) times the largest entry below it in its column (the
//               partial-pivoting test with KLU's default tolerance) makes factor() redo the
//               pivoting factorisation (counted in repivots()); it allocates only if the new
//               factors are larger than any before.
//   solve(b, x) L U z = P b, x = Q z, in preallocated work storage.
// All work is serial and in a fixed order: results do not depend on the thread count.
#pragma once

#include <vector>

#include "core/types.hpp"

namespace stiffbench {

template <class Scalar>
class SparseRefactorLu {
 public:
  using SparseM = Eigen::SparseMatrix<Scalar>;  // compressed, column-major
  using CVector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;

  // The pattern of every later A (compressed).
  void analyze(const SparseM& pattern);
  // False if A is numerically singular (no nonzero pivot in a column).
  bool factor(const SparseM& a);
  // x = A⁻¹ b with the last factorisation (x may not alias b).
  void solve(const CVector& b, CVector& x);

  // Pivoting factorisations after the first (the refactorisation's pivot test failed).
  long repivots() const { return repivots_; }
  // Entries of L (with its unit diagonal) and U.
  Index factor_nonzeros() const { return static_cast<Index>(li_.size() + ui_.size()); }

  static constexpr double diag_tol = 0.1;
  static constexpr double refactor_tol = 1e-3;

 private:
  bool pivoting_factor(const SparseM& a);
  bool refactor(const SparseM& a);
  int reach(const SparseM& a, int col);

  int n_ = 0;
  std::vector<int> q_;                  // column ordering: step k factors column q_[k]
  std::vector<int> a_outer_, a_inner_;  // A's pattern
  std::vector<int> a_step_row_;         // pinv_ of each entry's row (refactorisation)
  std::vector<int> pinv_;               // row i of A is row pinv_[i] of P A
  std::vector<int> lp_, li_, up_, ui_;  // L (unit diagonal first) and U (diagonal last)
  std::vector<Scalar> lx_, ux_;
  std::vector<int> xi_, stack_, pstack_;  // depth-first search
  std::vector<int> mark_;
  int stamp_ = 0;
  std::vector<Scalar> x_;  // dense work column
  bool factored_ = false;  // the patterns of L and U exist
  long repivots_ = 0;
};

}  // namespace stiffbench

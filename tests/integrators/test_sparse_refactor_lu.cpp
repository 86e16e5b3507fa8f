// SparseRefactorLu (integrators/solvers/sparse_refactor_lu.hpp): solutions checked against an
// independent computation, Eigen's dense PartialPivLU of the same matrix; the refactorisation
// path (same pattern, new values) and its fall-back to a new pivoting factorisation.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <complex>
#include <random>

#include "integrators/solvers/sparse_refactor_lu.hpp"

namespace stiffbench {
namespace {

// n×n: a diagonal, the two off-diagonals and 4 random entries a column; values uniform in
// [-1, 1] (+ `diag` on the diagonal), from `seed`. The pattern depends only on n.
template <class Scalar>
Eigen::SparseMatrix<Scalar> random_matrix(int n, double diag, unsigned seed) {
  std::mt19937 pattern_rng(7), value_rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> row(0, n - 1);
  const auto value = [&] {
    if constexpr (std::is_same_v<Scalar, double>)
      return u(value_rng);
    else
      return Scalar(u(value_rng), u(value_rng));
  };
  std::vector<Eigen::Triplet<Scalar>> t;
  for (int c = 0; c < n; ++c) {
    for (int r = std::max(0, c - 1); r <= std::min(n - 1, c + 1); ++r)
      t.emplace_back(r, c, value() + (r == c ? Scalar(diag) : Scalar(0)));
    for (int k = 0; k < 4; ++k) t.emplace_back(row(pattern_rng), c, value());
  }
  Eigen::SparseMatrix<Scalar> a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  a.makeCompressed();
  return a;
}

template <class Scalar>
double error_against_dense(SparseRefactorLu<Scalar>& lu, const Eigen::SparseMatrix<Scalar>& a) {
  using V = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  using M = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  const V b = V::LinSpaced(a.rows(), Scalar(1), Scalar(-2));
  V x;
  lu.solve(b, x);
  const V ref = Eigen::PartialPivLU<M>(M(a)).solve(b);
  return (x - ref).norm() / ref.norm();
}

template <class Scalar>
void check_refactorisation() {
  const int n = 60;
  SparseRefactorLu<Scalar> lu;
  auto a = random_matrix<Scalar>(n, 0.0, 1);  // no dominant diagonal: rows are exchanged
  lu.analyze(a);
  ASSERT_TRUE(lu.factor(a));
  EXPECT_LT(error_against_dense(lu, a), 1e-12);
  // New values in the same pattern, diagonally dominant: the pivots of the first factorisation
  // pass the 1e-3 test or are replaced; the solution is that of the new matrix either way.
  for (unsigned seed = 2; seed < 6; ++seed) {
    a = random_matrix<Scalar>(n, 3.0 + seed, seed);
    ASSERT_TRUE(lu.factor(a));
    EXPECT_LT(error_against_dense(lu, a), 1e-12) << seed;
  }
  EXPECT_GE(lu.factor_nonzeros(), a.nonZeros());  // L and U hold at least A's entries
}

TEST(SparseRefactorLu, RealAndComplexSolvesMatchDenseLu) {
  check_refactorisation<double>();
  check_refactorisation<std::complex<double>>();
}

// [[4, 1], [1, 4]] factors with the diagonal pivots (4 ≥ 0.1·1); the same pattern with the values
// [[0, 1], [1, 0]] makes the refactorised first pivot 0, so factor() exchanges the rows in a new
// pivoting factorisation (repivots() = 1). Exact solutions (Cramer's rule): x = ((4 b1 - b2)/15,
// (4 b2 - b1)/15) for the first, x = (b2, b1) for the second.
TEST(SparseRefactorLu, ZeroPivotInRefactorisationRepivots) {
  Eigen::SparseMatrix<double> a(2, 2);
  a.insert(0, 0) = 4;
  a.insert(1, 0) = 1;
  a.insert(0, 1) = 1;
  a.insert(1, 1) = 4;
  a.makeCompressed();
  SparseRefactorLu<double> lu;
  lu.analyze(a);
  ASSERT_TRUE(lu.factor(a));
  const Vec b = Vec::LinSpaced(2, 3.0, 5.0);  // b = (3, 5)
  Vec x;
  lu.solve(b, x);
  EXPECT_NEAR(x[0], (4 * 3.0 - 5.0) / 15, 1e-15);  // (4 b1 - b2)/15
  EXPECT_NEAR(x[1], (4 * 5.0 - 3.0) / 15, 1e-15);
  a.coeffRef(0, 0) = 0;  // explicit zeros stay in the compressed pattern
  a.coeffRef(1, 1) = 0;
  ASSERT_EQ(a.nonZeros(), 4);
  EXPECT_EQ(lu.repivots(), 0);
  ASSERT_TRUE(lu.factor(a));
  EXPECT_EQ(lu.repivots(), 1);
  lu.solve(b, x);
  EXPECT_EQ(x[0], 5.0);
  EXPECT_EQ(x[1], 3.0);
  // A singular matrix with this pattern: no nonzero pivot in the second column.
  a.coeffRef(0, 0) = 1;
  a.coeffRef(1, 0) = 1;
  a.coeffRef(0, 1) = 1;
  a.coeffRef(1, 1) = 1;
  EXPECT_FALSE(lu.factor(a));
}

}  // namespace
}  // namespace stiffbench

#include "core/lanczos.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

namespace stiffbench {

std::pair<double, double> lanczos_extreme_eigenvalues(Index n, const SymmetricOperator& apply,
                                                      const LanczosOptions& options) {
  // Lanczos with full reorthogonalisation (classical Gram–Schmidt, twice).
  const Index max_iter = std::min(n, options.max_iter);
  Mat q(n, max_iter);
  Vec alpha(max_iter), beta(max_iter), w(n);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (Index i = 0; i < n; ++i) q(i, 0) = uniform(rng);
  q.col(0).normalize();
  double lo = 0.0, hi = 0.0;
  Eigen::SelfAdjointEigenSolver<Mat> tri;
  for (Index j = 0; j < max_iter; ++j) {
    apply(q.col(j), w);
    alpha[j] = q.col(j).dot(w);
    for (int pass = 0; pass < 2; ++pass) {
      const Vec coeff = q.leftCols(j + 1).transpose() * w;
      w.noalias() -= q.leftCols(j + 1) * coeff;
    }
    beta[j] = w.norm();
    const double tiny = 1e-14 * std::max({std::abs(alpha[j]), beta[j], 1e-300});
    // The tridiagonal eigenproblem costs O(j²) or more: solve it every step while the basis is
    // small, then every fifth step.
    if (j >= 50 && j % 5 != 4 && j + 1 < max_iter && beta[j] > tiny) {
      q.col(j + 1) = w / beta[j];
      continue;
    }
    tri.computeFromTridiagonal(alpha.head(j + 1), beta.head(j), Eigen::ComputeEigenvectors);
    const Vec& theta = tri.eigenvalues();
    lo = theta[0];
    hi = theta[j];
    const double scale = std::max(std::abs(lo), std::abs(hi));
    // Residual ‖S y - θ y‖ of the Ritz pair = β_j |last component of the eigenvector of T|.
    const double res_lo = beta[j] * std::abs(tri.eigenvectors()(j, 0));
    const double res_hi = beta[j] * std::abs(tri.eigenvectors()(j, j));
    const bool invariant_subspace = beta[j] <= 1e-14 * std::max(scale, 1e-300);
    if (invariant_subspace || j + 1 == max_iter ||
        std::max(res_lo, res_hi) <= options.rel_tol * scale)
      break;
    q.col(j + 1) = w / beta[j];
  }
  return {lo, hi};
}

}  // namespace stiffbench

#include "core/lanczos.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

namespace stiffbench {

namespace {

// The extreme Ritz values of the tridiagonal T_j (alpha[0..j], beta[0..j-1]) and whether to stop
// after step j: the Krylov space is invariant, the step limit is reached, or both extreme Ritz
// pairs have residual ‖S y - θ y‖ = β_j |last component of T's eigenvector| <= rel_tol · max|θ|.
struct RitzCheck {
  Eigen::SelfAdjointEigenSolver<Mat> tri;
  double lo = 0.0, hi = 0.0;

  bool done(const Vec& alpha, const Vec& beta, Index j, Index max_iter, double rel_tol) {
    tri.computeFromTridiagonal(alpha.head(j + 1), beta.head(j), Eigen::ComputeEigenvectors);
    const Vec& theta = tri.eigenvalues();
    lo = theta[0];
    hi = theta[j];
    const double scale = std::max(std::abs(lo), std::abs(hi));
    const double res_lo = beta[j] * std::abs(tri.eigenvectors()(j, 0));
    const double res_hi = beta[j] * std::abs(tri.eigenvectors()(j, j));
    const bool invariant_subspace = beta[j] <= 1e-14 * std::max(scale, 1e-300);
    return invariant_subspace || j + 1 == max_iter || std::max(res_lo, res_hi) <= rel_tol * scale;
  }
};

// The tridiagonal eigenproblem costs O(j²) or more: solve it every step while the basis is
// small, then every fifth step (and always at the last step and on a breakdown).
bool check_now(Index j, Index max_iter, double alpha, double beta) {
  const double tiny = 1e-14 * std::max({std::abs(alpha), beta, 1e-300});
  return j < 50 || j % 5 == 4 || j + 1 == max_iter || beta <= tiny;
}

Vec start_vector(Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Vec q(n);
  for (Index i = 0; i < n; ++i) q[i] = uniform(rng);
  q.normalize();
  return q;
}

}  // namespace

std::pair<double, double> lanczos_extreme_eigenvalues(Index n, const SymmetricOperator& apply,
                                                      const LanczosOptions& options) {
  const Index max_iter = std::min(n, options.max_iter);
  Vec alpha(max_iter), beta(max_iter), w(n);
  RitzCheck ritz;
  if (8.0 * static_cast<double>(n) * static_cast<double>(max_iter) > options.max_basis_bytes) {
    // The three-term recurrence alone (O(n) memory, O(n) work a step besides apply). Orthogonality
    // is lost as Ritz values converge, which adds copies of converged values but does not move
    // the extreme ones (Paige; Golub & Van Loan 10.3).
    Vec q = start_vector(n, options.seed), q_prev = Vec::Zero(n);
    for (Index j = 0; j < max_iter; ++j) {
      apply(q, w);
      alpha[j] = q.dot(w);
      w.noalias() -= alpha[j] * q;
      if (j > 0) w.noalias() -= beta[j - 1] * q_prev;
      beta[j] = w.norm();
      if (check_now(j, max_iter, alpha[j], beta[j]) &&
          ritz.done(alpha, beta, j, max_iter, options.rel_tol))
        break;
      q_prev.swap(q);
      q = w / beta[j];
    }
    return {ritz.lo, ritz.hi};
  }
  // Full reorthogonalisation (classical Gram–Schmidt, twice) against the stored basis.
  Mat q(n, max_iter);
  q.col(0) = start_vector(n, options.seed);
  for (Index j = 0; j < max_iter; ++j) {
    apply(q.col(j), w);
    alpha[j] = q.col(j).dot(w);
    for (int pass = 0; pass < 2; ++pass) {
      const Vec coeff = q.leftCols(j + 1).transpose() * w;
      w.noalias() -= q.leftCols(j + 1) * coeff;
    }
    beta[j] = w.norm();
    if (check_now(j, max_iter, alpha[j], beta[j]) &&
        ritz.done(alpha, beta, j, max_iter, options.rel_tol))
      break;
    q.col(j + 1) = w / beta[j];
  }
  return {ritz.lo, ritz.hi};
}

}  // namespace stiffbench

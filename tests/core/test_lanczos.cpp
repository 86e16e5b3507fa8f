// Lanczos extreme eigenvalues (core/lanczos.hpp) against matrices with known spectra: exact when
// the Krylov space fills up, inside the spectrum when capped, and the same numbers on every call.
#include <gtest/gtest.h>

#include <cmath>

#include "core/lanczos.hpp"

namespace stiffbench {
namespace {

// diag(1, 2, ..., n) applied as an operator.
SymmetricOperator diagonal(Index n) {
  return [n](const Vec& u, Vec& out) {
    for (Index i = 0; i < n; ++i) out[i] = static_cast<double>(i + 1) * u[i];
  };
}

TEST(Lanczos, FindsBothEndsOfADiagonalSpectrum) {
  const auto [lo, hi] = lanczos_extreme_eigenvalues(40, diagonal(40));
  EXPECT_NEAR(lo, 1.0, 1e-8);
  EXPECT_NEAR(hi, 40.0, 1e-8);
}

TEST(Lanczos, CappedRunStaysInsideTheSpectrumAndRepeatsExactly) {
  LanczosOptions opt;
  opt.max_iter = 5;
  const auto [lo, hi] = lanczos_extreme_eigenvalues(200, diagonal(200), opt);
  EXPECT_GE(lo, 1.0);
  EXPECT_LE(hi, 200.0);
  EXPECT_LT(lo, hi);
  const auto again = lanczos_extreme_eigenvalues(200, diagonal(200), opt);
  EXPECT_EQ(again.first, lo);
  EXPECT_EQ(again.second, hi);
}

// The 1D Laplacian tridiag(-1, 2, -1) of size n: eigenvalues 2 - 2 cos(kπ/(n+1)).
TEST(Lanczos, LaplacianEigenvaluesInClosedForm) {
  const Index n = 30;
  const SymmetricOperator laplacian = [n](const Vec& u, Vec& out) {
    for (Index i = 0; i < n; ++i)
      out[i] = 2 * u[i] - (i > 0 ? u[i - 1] : 0.0) - (i + 1 < n ? u[i + 1] : 0.0);
  };
  const auto [lo, hi] = lanczos_extreme_eigenvalues(n, laplacian);
  const double pi = std::acos(-1.0);
  EXPECT_NEAR(lo, 2 - 2 * std::cos(pi / (n + 1)), 1e-9);
  EXPECT_NEAR(hi, 2 - 2 * std::cos(n * pi / (n + 1)), 1e-9);
}

// The recurrence without a stored basis (chosen when the basis would exceed max_basis_bytes; 0
// forces it here): the same ends of diag(1, ..., 400) as the stored basis, to the stopping
// tolerance.
TEST(Lanczos, RecurrenceWithoutStoredBasisFindsTheSameEnds) {
  LanczosOptions plain;
  plain.max_basis_bytes = 0;
  const auto [lo, hi] = lanczos_extreme_eigenvalues(400, diagonal(400), plain);
  const auto full = lanczos_extreme_eigenvalues(400, diagonal(400));
  EXPECT_NEAR(lo, 1.0, 1e-8);
  EXPECT_NEAR(hi, 400.0, 1e-8);
  EXPECT_NEAR(lo, full.first, 1e-8);
  EXPECT_NEAR(hi, full.second, 1e-8);
}

// A capped run on a spectrum whose ends are clustered (the 1D Laplacian of size 5,000: gaps of
// about 1.2e-6 at both ends): the recurrence's extreme Ritz values lie inside the spectrum
// (closed form) and agree with the stored basis's to 1e-6 relative.
TEST(Lanczos, RecurrenceMatchesTheStoredBasisOnAClusteredSpectrum) {
  const Index n = 5000;
  const SymmetricOperator laplacian = [n](const Vec& u, Vec& out) {
    for (Index i = 0; i < n; ++i)
      out[i] = 2 * u[i] - (i > 0 ? u[i - 1] : 0.0) - (i + 1 < n ? u[i + 1] : 0.0);
  };
  LanczosOptions full;
  full.max_iter = 150;
  LanczosOptions plain = full;
  plain.max_basis_bytes = 0;
  const auto [lo, hi] = lanczos_extreme_eigenvalues(n, laplacian, plain);
  const auto stored = lanczos_extreme_eigenvalues(n, laplacian, full);
  const double pi = std::acos(-1.0);
  EXPECT_GE(lo, 2 - 2 * std::cos(pi / (n + 1)) - 1e-12);
  EXPECT_LE(hi, 2 - 2 * std::cos(n * pi / (n + 1)) + 1e-12);
  EXPECT_NEAR(hi, stored.second, 1e-6 * stored.second);
  EXPECT_NEAR(lo, stored.first, 1e-6 * stored.second);
}

}  // namespace
}  // namespace stiffbench

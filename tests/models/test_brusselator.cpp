// The 1D Brusselator with diffusion (models/problems/brusselator.hpp; Hairer, Nørsett & Wanner I
// §I.16, Hairer & Wanner II §IV.1): f at the initial state against a hand computation, the
// equilibrium u ≡ 1, v ≡ 3, the analytic banded Jacobian against finite differences, the
// stiffness bound, and two integrators agreeing on a short solve.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "core/ode_system.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

Vec rhs_at(const OdeSystem& sys, const Vec& y) {
  Vec f(sys.dimension());
  sys.rhs(0.0, y, f);
  return f;
}

// N = 3, α = 1/50: x_i = 1/4, 1/2, 3/4, sin(2π x_i) = 1, 0, -1, so u = (2, 1, 0), v = (3, 3, 3),
// and c = α (N+1)² = 16/50 = 0.32. With u_0 = u_4 = 1, v_0 = v_4 = 3:
//   u_1' = 1 + 2²·3 - 4·2 + c (1 - 4 + 1) = 5 - 0.64 = 4.36
//   v_1' = 3·2 - 2²·3 + c (3 - 6 + 3)     = -6
//   u_2' = 1 + 1·3 - 4·1 + c (2 - 2 + 0) = 0
//   v_2' = 3·1 - 1·3 + c (3 - 6 + 3)     = 0
//   u_3' = 1 + 0 - 0 + c (1 - 0 + 1)     = 1 + 0.64 = 1.64
//   v_3' = 0 - 0 + c (3 - 6 + 3)         = 0
// (sin(π) is 1.2e-16 in floating point, hence the 1e-14 tolerance.)
TEST(Brusselator, RhsAtInitialStateByHand) {
  auto sys = model("brusselator", {"n=3"});
  ASSERT_EQ(sys->dimension(), 6);
  const Vec y0 = sys->initial_state();
  const Vec expected_y0{{2.0, 3.0, 1.0, 3.0, 0.0, 3.0}};
  EXPECT_LT((y0 - expected_y0).lpNorm<Eigen::Infinity>(), 1e-14);
  const Vec f = rhs_at(*sys, y0);
  const Vec expected{{4.36, -6.0, 0.0, 0.0, 1.64, 0.0}};
  EXPECT_LT((f - expected).lpNorm<Eigen::Infinity>(), 1e-14) << f.transpose();
  ASSERT_TRUE(sys->end_time().has_value());
  EXPECT_EQ(*sys->end_time(), 10.0);
}

// u ≡ 1, v ≡ 3 equals the boundary values, so every second difference is 0, and the reaction
// terms are 1 + 1·3 - 4 = 0 and 3 - 1·3 = 0: f = 0 exactly, for every N and α.
TEST(Brusselator, BoundaryStateIsAnEquilibrium) {
  for (const char* n : {"n=1", "n=7", "n=64"}) {
    for (const char* alpha : {"alpha=0.02", "alpha=3"}) {
      SCOPED_TRACE(std::string(n) + " " + alpha);
      auto sys = model("brusselator", {n, alpha});
      Vec y(sys->dimension());
      for (Index k = 0; k < y.size(); ++k) y[k] = k % 2 == 0 ? 1.0 : 3.0;
      EXPECT_EQ(rhs_at(*sys, y).lpNorm<Eigen::Infinity>(), 0.0);
    }
  }
}

// The analytic Jacobian against central finite differences at the initial state and at random
// states (u, v in [0, 4]). f is quadratic in each single u_i and linear in each v_i, so central
// differences have no truncation error; what is left is rounding, about ε ‖f‖ / h with h ≈ √ε
// times the component: about 1e-10 (1 + ‖J‖max) here (measured at most 2.5e-10), and 1e-8 is
// far below any wrong entry (every entry is O(1) or O(c)). Also: 8N - 4 stored entries, all within
// the band |i - j| <= 2 of the interleaved ordering.
TEST(Brusselator, JacobianMatchesFiniteDifferencesAndIsBanded) {
  std::mt19937 rng(28);
  std::uniform_real_distribution<double> draw(0.0, 4.0);
  for (const char* n : {"n=1", "n=2", "n=5", "n=12"}) {
    SCOPED_TRACE(n);
    auto sys = model("brusselator", {n});
    const Index dim = sys->dimension();
    std::vector<Vec> states{sys->initial_state()};
    for (int s = 0; s < 3; ++s) {
      Vec y(dim);
      for (Index k = 0; k < dim; ++k) y[k] = draw(rng);
      states.push_back(y);
    }
    for (const Vec& y : states) {
      SparseMat j;
      sys->jacobian(0.0, y, j);
      ASSERT_EQ(j.rows(), dim);
      ASSERT_EQ(j.cols(), dim);
      EXPECT_EQ(j.nonZeros(), 4 * dim - 4);  // 8N - 4
      for (int c = 0; c < j.outerSize(); ++c)
        for (SparseMat::InnerIterator it(j, c); it; ++it)
          EXPECT_LE(std::abs(it.row() - it.col()), 2);
      const Mat dense(j);
      const Mat fd = finite_difference_jacobian(*sys, 0.0, y);
      const double scale = 1.0 + dense.lpNorm<Eigen::Infinity>();
      EXPECT_LT((dense - fd).lpNorm<Eigen::Infinity>(), 1e-8 * scale);
    }
  }
}

// stiffness() bounds the spectral radius (Gershgorin) and, at the equilibrium, is at most the
// diffusion part's 4c plus the reaction block's largest row sum: the block is
// [[2uv - 4, u²], [3 - 2uv, -u²]] = R = [[2, 1], [-3, -1]], row sums 3 and 4, so <= 4c + 4.
// The spectrum is known exactly there: with the interleaved ordering J = c L ⊗ I₂ + I_N ⊗ R (L
// the Dirichlet second-difference matrix), the two terms commute, so the eigenvalues are
// -μ_k + r with μ_k = 4c sin²(kπ/(2(N+1))) and r = (1 ± i√3)/2 (trace R = 1, det R = 1). For
// N = 40, c = 41²/50 = 33.62, ρ(J) = |-μ_40 + (1 + i√3)/2| = 133.7855 (μ_40 = 134.2827).
// Measured: bound 136.48 <= 4c + 4 = 138.48.
TEST(Brusselator, StiffnessBoundsSpectralRadius) {
  auto sys = model("brusselator", {"n=40"});
  Vec y(sys->dimension());
  for (Index k = 0; k < y.size(); ++k) y[k] = k % 2 == 0 ? 1.0 : 3.0;
  const double c = 41.0 * 41.0 / 50.0;
  const auto rho_bound = sys->stiffness(0.0, y);
  ASSERT_TRUE(rho_bound.has_value());
  SparseMat j;
  sys->jacobian(0.0, y, j);
  const Eigen::VectorXcd eig = Eigen::EigenSolver<Mat>(Mat(j)).eigenvalues();
  const double rho = eig.cwiseAbs().maxCoeff();
  EXPECT_GE(*rho_bound, rho);
  EXPECT_LE(*rho_bound, 4.0 * c + 4.0);
  const double s = std::sin(40.0 * std::numbers::pi / 82.0);
  const double mu = 4.0 * c * s * s;
  EXPECT_NEAR(rho, std::abs(std::complex<double>(0.5 - mu, std::sqrt(3.0) / 2.0)), 1e-9 * rho);
}

// Two different integrators on N = 16 to t = 2 (past the first steep front of the oscillation):
// CVODE BDF and Radau IIA (radau5), both at rtol = atol = 1e-9, agree to 1e-6 in max-norm
// (each run's global error is a small multiple of its tolerance; measured difference 1.9e-8).
// This checks that the model runs end to end with a BDF and a Radau method to the same answer.
TEST(Brusselator, CvodeAndRadau5Agree) {
  auto sys = model("brusselator", {"n=16"});
  AdaptiveOptions opt;
  opt.t_end = 2.0;
  Vec results[2];
  int i = 0;
  for (const char* name : {"cvode_bdf", "radau5"}) {
    SCOPED_TRACE(name);
    auto integ = make(name, {"rtol=1e-9", "atol=1e-9"});
    const RunResult r = run_adaptive(*sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::ok);
    results[i++] = r.y;
  }
  EXPECT_LT((results[0] - results[1]).lpNorm<Eigen::Infinity>(), 1e-6);
  // The run moved away from the initial state (u_8 starts at 1 + sin(16π/17) = 1.18).
  EXPECT_GT((results[0] - sys->initial_state()).lpNorm<Eigen::Infinity>(), 0.1);
}

// Bad parameters are BadInput naming the parameter (the registry's bounds: n >= 1, α > 0).
TEST(Brusselator, BadParametersAreRefused) {
  for (const char* bad : {"n=0", "n=-3", "alpha=0", "alpha=-0.02"}) {
    SCOPED_TRACE(bad);
    try {
      model("brusselator", {bad});
      ADD_FAILURE() << "no BadInput";
    } catch (const BadInput& e) {
      const std::string key = std::string(bad).substr(0, std::string(bad).find('='));
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace stiffbench

// Self-checks of every registered Butcher tableau and splitting method.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "core/driver.hpp"
#include "experiments/catalog.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "integrators/symplectic/kick_drift.hpp"
#include "models/problems/dahlquist.hpp"

namespace stiffbench {
// Readable test parameter names instead of byte dumps.
inline void PrintTo(const ButcherTableau& t, std::ostream* os) { *os << t.name; }
inline void PrintTo(const KickDriftCoefficients& t, std::ostream* os) { *os << t.name; }
namespace {

class TableauTest : public ::testing::TestWithParam<ButcherTableau> {};

TEST_P(TableauTest, RowSumsAreNodes) { EXPECT_LE(GetParam().row_sum_defect(), 1e-15); }

// Butcher's order conditions hold up to the claimed order and fail at the next one, so the
// claimed order is exactly the order (a tableau claiming too little would also be caught).
TEST_P(TableauTest, OrderConditionsHoldExactlyToClaimedOrder) {
  const ButcherTableau& t = GetParam();
  for (int p = 1; p <= t.order; ++p) EXPECT_LE(t.order_defect(p), 1e-14) << "order " << p;
  EXPECT_GT(t.order_defect(t.order + 1), 1e-6);
  EXPECT_EQ(t.satisfied_order(), t.order);
}

// One step of the generic stepper on y' = λy (λ complex, as a 2-D real system) multiplies
// y0 by R(hλ): the stepper and the tableau's stability function must agree.
TEST_P(TableauTest, StabilityFunctionMatchesOneStep) {
  const ButcherTableau& t = GetParam();
  for (const std::complex<double> z : {std::complex<double>(-0.7, 0.3), {-2.0, 1.5}, {0.2, -1.1}}) {
    Dahlquist sys(z, {1.0, 0.0});
    ExplicitRungeKutta rk(t, "");
    Vec y = sys.initial_state();
    SolveStats stats;
    rk.reset(sys, 0.0, y);
    rk.step(sys, 0.0, y, 1.0, stats);
    const std::complex<double> r = t.stability(z);
    EXPECT_NEAR(y[0], r.real(), 1e-14);
    EXPECT_NEAR(y[1], r.imag(), 1e-14);
  }
}

// For an explicit s-stage method of order p = s (s <= 4), R(z) is the degree-s Taylor
// polynomial of e^z: any order-p method agrees with e^z to O(z^{p+1}) on y' = λy.
TEST_P(TableauTest, StabilityFunctionApproximatesExponential) {
  const ButcherTableau& t = GetParam();
  const std::complex<double> z1(1e-2, 5e-3), z2 = z1 / 2.0;
  const double e1 = std::abs(t.stability(z1) - std::exp(z1));
  const double e2 = std::abs(t.stability(z2) - std::exp(z2));
  EXPECT_NEAR(std::log2(e1 / e2), t.order + 1, 0.05);
}

INSTANTIATE_TEST_SUITE_P(Explicit, TableauTest, ::testing::ValuesIn(explicit_tableaux()),
                         [](const auto& param_info) { return param_info.param.name; });

// Real-axis stability limit of classic RK4, -2.7853 (docs/reference-values.md table, Hairer–Wanner
// II Fig. IV.2.1), found by bisection on |R(x)| = 1.
TEST(TableauStability, Rk4RealAxisLimit) {
  const ButcherTableau* rk4 = nullptr;
  for (const auto& t : explicit_tableaux())
    if (t.name == "rk4") rk4 = &t;
  ASSERT_NE(rk4, nullptr);
  double lo = -3.0, hi = -2.0;  // |R(lo)| > 1, |R(hi)| < 1
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::abs(rk4->stability(mid)) > 1 ? lo : hi) = mid;
  }
  EXPECT_NEAR(lo, -2.7853, 5e-5);
  // Imaginary-axis limit 2√2 (same table): |R(iy)| = 1 exactly there.
  EXPECT_NEAR(std::abs(rk4->stability({0.0, 2.0 * std::numbers::sqrt2})), 1.0, 1e-12);
  EXPECT_GT(std::abs(rk4->stability({0.0, 2.0 * std::numbers::sqrt2 + 0.01})), 1.0);
}

TEST(TableauRegistry, EveryExplicitTableauIsRegistered) {
  for (const auto& t : explicit_tableaux()) {
    const auto* e = integrator_registry().find(t.name);
    ASSERT_NE(e, nullptr) << t.name;
    EXPECT_EQ(e->info.order, t.order);
    EXPECT_EQ(e->info.stages, t.stages());
    EXPECT_EQ(e->info.family, Family::explicit_rk);
  }
}

class SplittingTest : public ::testing::TestWithParam<KickDriftCoefficients> {};

TEST_P(SplittingTest, OrderConditions) {
  const KickDriftCoefficients& c = GetParam();
  EXPECT_LE(c.order_defect(1), 1e-15);
  if (c.order >= 2) {
    EXPECT_LE(c.order_defect(2), 1e-15);
  } else {
    EXPECT_GT(c.order_defect(2), 1e-6);  // first order only: the second condition fails
  }
}

INSTANTIATE_TEST_SUITE_P(Symplectic, SplittingTest, ::testing::ValuesIn(kick_drift_coefficients()),
                         [](const auto& param_info) { return param_info.param.name; });

}  // namespace
}  // namespace stiffbench

// Self-checks of every registered Butcher tableau and splitting method.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "integrators/adaptive/embedded_rk.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/implicit/gauss.hpp"
#include "integrators/implicit/radau5.hpp"
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

// ---- Checks at construction (ButcherTableau::validate) ----------------------------------------

const ButcherTableau& named(const std::string& name) {
  for (const auto* list : {&explicit_tableaux(), &embedded_tableaux()})
    for (const auto& t : *list)
      if (t.name == name) return t;
  throw std::logic_error("no tableau " + name);
}

// The message of the BadInput `f` throws (empty when it does not throw).
template <class F>
std::string refusal(F f) {
  try {
    f();
  } catch (const BadInput& e) {
    return e.what();
  }
  return {};
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// Every built-in tableau passes the checks its stepper applies (explicit, embedded, DIRK and
// ESDIRK with their shape; Gauss and Radau IIA as full tableaux).
TEST(TableauValidation, EveryBuiltInTableauPasses) {
  for (const auto* list : {&explicit_tableaux(), &embedded_tableaux()})
    for (ButcherTableau t : *list) {
      EXPECT_EQ(t.defect(ButcherTableau::Shape::explicit_rk), "") << t.name;
      EXPECT_EQ(t.satisfied_stage_order(), 1) << t.name;  // explicit: C(1) only
    }
  for (const auto* list : {&implicit_tableaux(), &esdirk_tableaux()})
    for (const ButcherTableau& t : *list)
      EXPECT_EQ(t.defect(ButcherTableau::Shape::diagonally_implicit), "") << t.name;
  EXPECT_EQ(gauss_tableau(2).defect(), "");
  EXPECT_EQ(gauss_tableau(3).defect(), "");
  EXPECT_EQ(radau5_tableau().defect(), "");
  // Collocation methods of s stages have stage order s (Hairer–Wanner II, §IV.5).
  EXPECT_EQ(gauss_tableau(3).satisfied_stage_order(), 3);
  EXPECT_EQ(radau5_tableau().satisfied_stage_order(), 3);
  EXPECT_TRUE(named("dopri5").coefficients_fsal());
  EXPECT_TRUE(named("bs3").coefficients_fsal());
  EXPECT_FALSE(named("rkf45").coefficients_fsal());
}

// An empty c is completed from the row sums (it used to crash the stepper): the completed rk4
// gives the same step, bit for bit, as the one with c typed in.
TEST(TableauValidation, EmptyNodesAreCompletedFromRowSums) {
  ButcherTableau t = named("rk4");
  t.c = Vec();
  t.name = "rk4_without_c";
  ExplicitRungeKutta completed(t, "");
  ExplicitRungeKutta original(named("rk4"), "");
  ASSERT_EQ(completed.tableau().c.size(), 4);
  EXPECT_EQ(completed.tableau().c, named("rk4").c);
  Dahlquist sys({-1.0, 2.0}, {1.0, 0.5});
  Vec y1 = sys.initial_state(), y2 = y1;
  SolveStats stats;
  completed.reset(sys, 0.0, y1);
  original.reset(sys, 0.0, y2);
  completed.step(sys, 0.0, y1, 0.1, stats);
  original.step(sys, 0.0, y2, 0.1, stats);
  EXPECT_EQ(y1, y2);
}

TEST(TableauValidation, EachDefectIsRefusedByName) {
  using Shape = ButcherTableau::Shape;
  // c given but not the row sums (heun's c2 = 1 typed as 0.9).
  ButcherTableau t = named("heun");
  t.c[1] = 0.9;
  std::string m = refusal([&] { ExplicitRungeKutta(t, ""); });
  EXPECT_TRUE(contains(m, "tableau 'heun'") && contains(m, "c[1] = 0.9")) << m;
  // Sizes: A 2x2 with three weights; c of the wrong length; b_embedded of the wrong length.
  t = named("heun");
  t.b = Vec::Constant(3, 1.0 / 3.0);
  m = refusal([&] { t.validate(); });
  EXPECT_TRUE(contains(m, "A is 2x2, b has 3 entries")) << m;
  t = named("heun");
  t.c = Vec::Zero(3);
  m = refusal([&] { t.validate(); });
  EXPECT_TRUE(contains(m, "c has 3 entries, b has 2")) << m;
  t = named("dopri5");
  t.b_embedded = Vec::Zero(6);
  m = refusal([&] { EmbeddedRungeKutta(t, "", {}); });
  EXPECT_TRUE(contains(m, "b_embedded has 6 entries, b has 7")) << m;
  // Claimed order not met: heun claiming 3 (bᵀc² = 1/2, not 1/3: the defect is 1/6).
  t = named("heun");
  t.order = 3;
  m = refusal([&] { ExplicitRungeKutta(t, ""); });
  EXPECT_TRUE(
      contains(m, "order 3 claimed but the condition of tree [t^2] (order 3) has residual 0.167"))
      << m;
  // Weights that do not sum to 1 (order 1 fails).
  t = named("rk4");
  t.b[0] = 0.2;
  m = refusal([&] { ExplicitRungeKutta(t, ""); });
  EXPECT_TRUE(contains(m, "tree t (order 1)") && contains(m, "sum to 1.03")) << m;
  // Embedded weights that do not sum to 1 (dopri5's b̂_1 raised by 0.01).
  t = named("dopri5");
  t.b_embedded[0] += 0.01;
  m = refusal([&] { EmbeddedRungeKutta(t, "", {}); });
  EXPECT_TRUE(contains(m, "embedded order 4") && contains(m, "embedded weights sum to 1.01")) << m;
  // An embedded pair without embedded weights.
  t = named("rk4");
  m = refusal([&] { EmbeddedRungeKutta(t, "", {}); });
  EXPECT_TRUE(contains(m, "no embedded weights")) << m;
  // Not explicit: a diagonal entry in an explicit stepper; above the diagonal for a DIRK.
  t = named("heun");
  t.a(0, 0) = 0.5;
  t.a(1, 0) = 0.5;  // keep the row sums equal to c
  t.c << 0.5, 0.5;
  t.order = 1;
  m = refusal([&] { ExplicitRungeKutta(t, ""); });
  EXPECT_TRUE(contains(m, "strictly lower triangular: a(0,0) = 0.5")) << m;
  EXPECT_EQ(t.defect(Shape::diagonally_implicit), "");
  t.a(0, 1) = 0.1;
  t.c[0] = 0.6;
  EXPECT_TRUE(contains(t.defect(Shape::diagonally_implicit), "a(0,1) = 0.1")) << t.defect();
  // FSAL claimed where the last row of A is not b (rk4).
  t = named("rk4");
  t.fsal = true;
  m = refusal([&] { ExplicitRungeKutta(t, ""); });
  EXPECT_TRUE(contains(m, "fsal")) << m;
  // A stage order above what C(q) gives (rk4 claims 2; C(2) fails at stage 2: a21 c1 = 0 while
  // c2^2/2 = 1/8).
  t = named("rk4");
  t.stage_order = 2;
  m = refusal([&] { ExplicitRungeKutta(t, ""); });
  EXPECT_TRUE(contains(m, "claims stage order 2 but C(q) holds only for q = 1")) << m;
  // No order claimed at all.
  t = named("rk4");
  t.order = 0;
  m = refusal([&] { t.validate(); });
  EXPECT_TRUE(contains(m, "claims no order")) << m;
  // Not finite.
  t = named("rk4");
  t.b[3] = std::nan("");
  m = refusal([&] { t.validate(); });
  EXPECT_TRUE(contains(m, "not finite")) << m;
}

// Claims are checked up to order 8 (the rooted trees of core/theory/method_analysis.hpp): gauss6 is
// of order 2s = 6 exactly (Hairer & Wanner II, IV.5), so a claim of 8 fails at an order-7 tree, and
// a claim above 8 is checked up to 8.
TEST(TableauValidation, OrdersAreCheckedToEight) {
  ButcherTableau t = gauss_tableau(3);
  EXPECT_EQ(t.defect(), "");
  t.order = 8;
  EXPECT_TRUE(contains(t.defect(), "order 8 claimed but the condition of tree") &&
              contains(t.defect(), "(order 7)"))
      << t.defect();
  t.order = 6;
  t.b[0] += 1e-9;
  EXPECT_TRUE(contains(t.defect(), "tree t (order 1)")) << t.defect();
}

}  // namespace
}  // namespace stiffbench

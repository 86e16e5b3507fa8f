// Method analysis from coefficients (core/theory/method_analysis.hpp). Every figure is checked
// against an independent computation or a published value; each test says which. The tableaux are
// written here (not taken from the registry), so the test checks the analysis, not the tables.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <complex>
#include <map>
#include <numbers>
#include <optional>
#include <string>

#include "core/theory/method_analysis.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

ButcherTableau tableau(std::string name, int order, Mat a, Vec b) {
  ButcherTableau t;
  t.name = std::move(name);
  t.order = order;
  t.a = std::move(a);
  t.b = std::move(b);
  t.c = t.a.rowwise().sum();
  return t;
}

ButcherTableau rk4() {
  return tableau("rk4", 4, Mat{{0, 0, 0, 0}, {0.5, 0, 0, 0}, {0, 0.5, 0, 0}, {0, 0, 1, 0}},
                 Vec{{1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6}});
}

ButcherTableau ssprk3() {  // Shu & Osher (1988)
  return tableau("ssprk3", 3, Mat{{0, 0, 0}, {1, 0, 0}, {0.25, 0.25, 0}},
                 Vec{{1.0 / 6, 1.0 / 6, 2.0 / 3}});
}

ButcherTableau dopri5() {  // Dormand & Prince (1980)
  ButcherTableau t =
      tableau("dopri5", 5,
              Mat{{0, 0, 0, 0, 0, 0, 0},
                  {1.0 / 5, 0, 0, 0, 0, 0, 0},
                  {3.0 / 40, 9.0 / 40, 0, 0, 0, 0, 0},
                  {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0, 0},
                  {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0, 0},
                  {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0, 0},
                  {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84, 0}},
              Vec{{35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84, 0}});
  t.b_embedded = Vec{
      {5179.0 / 57600, 0, 7571.0 / 16695, 393.0 / 640, -92097.0 / 339200, 187.0 / 2100, 1.0 / 40}};
  t.embedded_order = 4;
  return t;
}

ButcherTableau radau_iia3() {  // Hairer & Wanner II, Table IV.5.6
  const double r = std::sqrt(6.0);
  return tableau("radau_iia3", 5,
                 Mat{{(88 - 7 * r) / 360, (296 - 169 * r) / 1800, (-2 + 3 * r) / 225},
                     {(296 + 169 * r) / 1800, (88 + 7 * r) / 360, (-2 - 3 * r) / 225},
                     {(16 - r) / 36, (16 + r) / 36, 1.0 / 9}},
                 Vec{{(16 - r) / 36, (16 + r) / 36, 1.0 / 9}});
}

ButcherTableau gauss6() {  // Hairer & Wanner II, Table IV.5.2
  const double r = std::sqrt(15.0);
  return tableau("gauss6", 6,
                 Mat{{5.0 / 36, 2.0 / 9 - r / 15, 5.0 / 36 - r / 30},
                     {5.0 / 36 + r / 24, 2.0 / 9, 5.0 / 36 - r / 24},
                     {5.0 / 36 + r / 30, 2.0 / 9 + r / 15, 5.0 / 36}},
                 Vec{{5.0 / 18, 4.0 / 9, 5.0 / 18}});
}

ButcherTableau sdirk3() {
  // Alexander (1977): γ the root of x³ − 3x² + 3x/2 − 1/6 in (1/6, 1/2) (Newton from 0.4358),
  // τ2 = (1 + γ)/2, b1 = −(6γ² − 16γ + 1)/4, b2 = (6γ² − 20γ + 5)/4.
  double g = 0.4358;
  for (int i = 0; i < 20; ++i) g -= (((g - 3) * g + 1.5) * g - 1.0 / 6) / ((3 * g - 6) * g + 1.5);
  const double t2 = (1 + g) / 2, b1 = -(6 * g * g - 16 * g + 1) / 4,
               b2 = (6 * g * g - 20 * g + 5) / 4;
  return tableau("sdirk3", 3, Mat{{g, 0, 0}, {t2 - g, g, 0}, {b1, b2, g}}, Vec{{b1, b2, g}});
}

// ---- Rooted trees -------------------------------------------------------------------------------

TEST(MethodAnalysis, RootedTreesCountsDensitySymmetry) {
  // Counts per order: OEIS A000081 (1, 1, 2, 4, 9, 20, 48, 115). Two identities check γ and σ
  // of every tree independently: Cayley's n^(n−1) labelled rooted trees = Σ_{|t|=n} n!/σ(t),
  // and the (n−1)! increasing labellings = Σ_{|t|=n} n!/(σ(t)γ(t)) (Butcher 2016, §30).
  const int counts[] = {1, 1, 2, 4, 9, 20, 48, 115};
  const auto& trees = rooted_trees();
  ASSERT_EQ(trees.size(), 200u);
  for (int n = 1; n <= 8; ++n) {
    int count = 0;
    double labelled = 0, increasing = 0, fact = std::tgamma(n + 1.0);
    for (const RootedTree& t : trees)
      if (t.order == n) {
        ++count;
        labelled += fact / t.symmetry;
        increasing += fact / (t.symmetry * t.density);
      }
    EXPECT_EQ(count, counts[n - 1]) << n;
    EXPECT_NEAR(labelled, std::pow(n, n - 1), 1e-9 * std::pow(n, n - 1)) << n;
    EXPECT_NEAR(increasing, std::tgamma(n), 1e-9 * std::tgamma(n)) << n;
  }
  // Names, γ, σ of the order-3 trees (HNW I, Table II.2.1).
  EXPECT_EQ(trees[2].name, "[t^2]");
  EXPECT_EQ(trees[2].density, 3.0);
  EXPECT_EQ(trees[2].symmetry, 2.0);
  EXPECT_EQ(trees[3].name, "[[t]]");
  EXPECT_EQ(trees[3].density, 6.0);
  EXPECT_EQ(trees[3].symmetry, 1.0);
}

// ---- Runge–Kutta --------------------------------------------------------------------------------

TEST(MethodAnalysis, Rk4OrderAndErrorCoefficients) {
  const MethodAnalysis m = analyze_runge_kutta(rk4(), "explicit_rk");
  EXPECT_EQ(m.order, 4);
  EXPECT_EQ(m.stage_order, 1);
  EXPECT_FALSE(m.fsal);
  // The nine order-5 conditions written out (Butcher 2016, Table 301(I)): Φ, γ, σ per tree;
  // τ = (bᵀΦ − 1/γ)/σ. Exact values (in rationals): 1/2880, 1/480, −1/480, 1/120, 1/160, −1/720,
  // −1/240, 1/480, −1/120: A^(5) = 0.0145045823431982 (Kennedy & Carpenter 2003 quote 1.450e-2),
  // max 1/120.
  const ButcherTableau t = rk4();
  const Vec& b = t.b;
  const Vec c = t.c, c2 = c.cwiseProduct(c), c3 = c2.cwiseProduct(c);
  const Mat& a = t.a;
  const Vec ac = a * c;
  const double cond[9][3] = {
      {b.dot(c3.cwiseProduct(c)), 5, 24},     {b.dot(c2.cwiseProduct(ac)), 10, 2},
      {b.dot(c.cwiseProduct(a * c2)), 15, 2}, {b.dot(c.cwiseProduct(a * ac)), 30, 1},
      {b.dot(ac.cwiseProduct(ac)), 20, 2},    {b.dot(a * c3), 20, 6},
      {b.dot(a * c.cwiseProduct(ac)), 40, 1}, {b.dot(a * (a * c2)), 60, 2},
      {b.dot(a * (a * ac)), 120, 1}};
  double sum2 = 0, max = 0, max_residual = 0;
  for (const auto& x : cond) {
    const double tau = (x[0] - 1 / x[1]) / x[2];
    sum2 += tau * tau;
    max = std::max(max, std::abs(tau));
    max_residual = std::max(max_residual, std::abs(x[0] - 1 / x[1]));
  }
  EXPECT_NEAR(m.error_norm_2, std::sqrt(sum2), 1e-15);
  EXPECT_NEAR(m.error_norm_2, 0.0145045823431982, 1e-15);
  EXPECT_NEAR(m.error_norm_max, 1.0 / 120, 1e-16);
  // The tall tree [[[[t]]]]: on y' = y only it has a non-zero elementary differential, so its τ
  // is the z⁵ coefficient of R(z) − e^z = −1/120 (R the degree-4 Taylor polynomial).
  bool found = false;
  for (const OrderCondition& x : m.conditions)
    if (x.name == "[[[[t]]]]") {
      found = true;
      EXPECT_NEAR(x.error_coefficient, -1.0 / 120, 1e-16);
    }
  EXPECT_TRUE(found);
  // Largest |bᵀΦ − 1/γ| of order 5: (Ac)ᵀ diag(b) (Ac) − 1/20 = 1/80 (tree [[t]^2]).
  EXPECT_NEAR(m.residual_by_order[4], max_residual, 1e-16);
  EXPECT_NEAR(m.residual_by_order[4], 1.0 / 80, 1e-16);
  EXPECT_LE(m.residual_by_order[3], 1e-15);
  EXPECT_DOUBLE_EQ(m.max_coefficient, 1.0);
  // R = 1 + z + z²/2 + z³/6 + z⁴/24 (Taylor), explicit: |R(∞)| infinite, not A-stable.
  ASSERT_EQ(m.p.size(), 5u);
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(m.p[k], 1.0 / std::tgamma(k + 1.0), 1e-16) << k;
  EXPECT_EQ(m.q, Polynomial{1.0});
  EXPECT_TRUE(std::isinf(m.r_infinity));
  EXPECT_FALSE(m.a_stable);
  EXPECT_FALSE(m.l_stable);
}

TEST(MethodAnalysis, Rk4AxisLimitsDissipationDispersion) {
  const MethodAnalysis m = analyze_runge_kutta(rk4(), "explicit_rk");
  // Imaginary axis: |R(iy)|² = 1 − y⁶/72 + y⁸/576 = 1 at y² = 8: 2√2. Real axis: R(−x) = 1 at
  // the real root of x³ − 4x² + 12x − 24 (R(−x) − 1 = −x(1 − x/2 + x²/6 − x³/24)), by bisection.
  EXPECT_NEAR(m.imag_axis_limit, 2 * std::numbers::sqrt2, 1e-12);
  double lo = 2, hi = 3;
  for (int i = 0; i < 80; ++i) {
    const double x = 0.5 * (lo + hi);
    (((x - 4) * x + 12) * x - 24 < 0 ? lo : hi) = x;
  }
  EXPECT_NEAR(m.real_axis_limit, lo, 1e-12);
  EXPECT_NEAR(m.real_axis_limit, 2.785293563405282, 1e-12);
  EXPECT_FALSE(m.real_axis_unbounded);
  // 1 − |R(iν)| = ν⁶/144 + O(ν⁸) (from |R|² above): dissipation order 6; log R(z) − z =
  // −z⁵/120 + O(z⁶), so arg R(iν) − ν = −ν⁵/120 + O(ν⁷): dispersion order 5.
  EXPECT_EQ(m.dissipation_order, 6);
  EXPECT_EQ(m.dispersion_order, 5);
  const auto curve = dissipation_dispersion({m.p, m.q}, 121);
  ASSERT_EQ(curve.size(), 121u);
  EXPECT_NEAR(curve.front().nu, 1e-2, 1e-16);
  EXPECT_NEAR(curve.back().nu, 10.0, 1e-12);
  for (const auto& x : curve)
    if (x.nu >= 0.03 && x.nu <= 0.1) {  // relative O(ν²) corrections below 0.4%
      const double nu = x.nu;
      EXPECT_NEAR((1 - x.amplification) / (std::pow(nu, 6) / 144), 1.0, 0.005) << nu;
      EXPECT_NEAR(x.phase_error / (-std::pow(nu, 5) / 120), 1.0, 0.005) << nu;
    }
  // Direct evaluation at ν = 10 (the last point): R(10i) = 1 − 50 + 10⁴/24 + i(10 − 10³/6); the
  // unwrapped phase differs from its principal argument by whole turns.
  const std::complex<double> r10(1 - 50 + 1e4 / 24, 10 - 1e3 / 6);
  EXPECT_NEAR(curve.back().amplification, std::abs(r10), 1e-9 * std::abs(r10));
  const double turns = (curve.back().phase_error + 10 - std::arg(r10)) / (2 * std::numbers::pi);
  EXPECT_NEAR(turns, std::round(turns), 1e-9);
}

TEST(MethodAnalysis, SspCoefficients) {
  // ssprk3: 1 (Shu & Osher 1988); rk4: 0 (Kraaijevanger 1991); the optimal 2nd-order 3-stage
  // method SSPRK(3,2), A = [[0],[1/2],[1/2,1/2]], b = 1/3: s − 1 = 2 (Ketcheson 2008).
  EXPECT_NEAR(ssp_coefficient(ssprk3()), 1.0, 1e-12);
  EXPECT_EQ(ssp_coefficient(rk4()), 0.0);
  const ButcherTableau ssp32 =
      tableau("ssp32", 2, Mat{{0, 0, 0}, {0.5, 0, 0}, {0.5, 0.5, 0}}, Vec::Constant(3, 1.0 / 3));
  EXPECT_NEAR(ssp_coefficient(ssp32), 2.0, 2e-12);
  EXPECT_NEAR(analyze_runge_kutta(ssprk3(), "explicit_rk").ssp_coefficient, 1.0, 1e-12);
  EXPECT_EQ(analyze_runge_kutta(radau_iia3(), "irk").ssp_coefficient, -1.0);
  // The definition directly (Kraaijevanger): K = [[A, 0], [bᵀ, 0]], absolutely monotonic at r
  // when K(I + rK)⁻¹ >= 0 and rK(I + rK)⁻¹1 <= 1. Holds at r = 1 (to round-off), fails at
  // 1 + 1e-6 for ssprk3; for rk4 fails already at r = 1e-6.
  auto monotonic = [](const ButcherTableau& t, double r) {
    const Index s = t.stages();
    Mat k = Mat::Zero(s + 1, s + 1);
    k.topLeftCorner(s, s) = t.a;
    k.block(s, 0, 1, s) = t.b.transpose();
    const Mat p = k * (Mat::Identity(s + 1, s + 1) + r * k).inverse();
    return p.minCoeff() >= -1e-14 && (r * p * Vec::Ones(s + 1)).maxCoeff() <= 1 + 1e-14;
  };
  EXPECT_TRUE(monotonic(ssprk3(), 1.0));
  EXPECT_FALSE(monotonic(ssprk3(), 1.0 + 1e-6));
  EXPECT_TRUE(monotonic(rk4(), 0.0));
  EXPECT_FALSE(monotonic(rk4(), 1e-6));
}

TEST(MethodAnalysis, Dopri5OrderEmbeddedFsal) {
  // Dormand & Prince (1980): order 5, embedded 4, FSAL (last row of A = b, first row 0).
  const MethodAnalysis m = analyze_runge_kutta(dopri5(), "explicit_rk");
  EXPECT_EQ(m.order, 5);
  EXPECT_EQ(m.embedded_order, 4);
  EXPECT_TRUE(m.fsal);
  EXPECT_GT(m.residual_by_order[5], 1e-6);
  // P = 1 + z + … + z⁵/120 + p6 z⁶ (b_7 = 0, so degree 6: bᵀA⁵1 = 1/600 (Hairer, Nørsett &
  // Wanner I, the stability function of DOPRI5 in §II.5/IV.2)).
  ASSERT_EQ(m.p.size(), 7u);
  EXPECT_NEAR(m.p[6], 1.0 / 600, 1e-15);
}

TEST(MethodAnalysis, RadauIIA) {
  // Radau IIA, s = 3: order 2s − 1 = 5, stage order 3 (HW II, Table IV.5.6), stiffly accurate;
  // R = the (2,3) Padé approximant: P = 1 + 2z/5 + z²/20, Q = 1 − 3z/5 + 3z²/20 − z³/60
  // (HW II, (IV.3.30)), so A- and L-stable, R(∞) = 0.
  const MethodAnalysis m = analyze_runge_kutta(radau_iia3(), "irk");
  EXPECT_EQ(m.order, 5);
  EXPECT_EQ(m.stage_order, 3);
  EXPECT_TRUE(m.stiffly_accurate);
  EXPECT_FALSE(m.fsal);
  const Polynomial p = {1, 0.4, 0.05}, q = {1, -0.6, 0.15, -1.0 / 60};
  ASSERT_EQ(m.p.size(), p.size());
  ASSERT_EQ(m.q.size(), q.size());
  for (std::size_t k = 0; k < p.size(); ++k) EXPECT_NEAR(m.p[k], p[k], 1e-14) << k;
  for (std::size_t k = 0; k < q.size(); ++k) EXPECT_NEAR(m.q[k], q[k], 1e-14) << k;
  EXPECT_EQ(m.r_infinity, 0.0);
  EXPECT_TRUE(m.a_stable);
  EXPECT_TRUE(m.l_stable);
  EXPECT_TRUE(m.real_axis_unbounded);
  EXPECT_TRUE(m.imag_axis_unbounded);
  EXPECT_GT(m.internal_amplification_real, 0.0);
}

TEST(MethodAnalysis, Gauss6) {
  // Gauss, s = 3: order 6, stage order 3; R = (3,3) Padé, P(z) = Q(−z) = 1 + z/2 + z²/10 +
  // z³/120: |R(iy)| = 1, A-stable, |R(∞)| = 1, not L-stable; no dissipation (|R(iν)| = 1 exactly)
  // and log R(z) − z = −z⁷/100800 + … (the Padé error constant 3!3!/(6!7!)), dispersion order 7.
  const MethodAnalysis m = analyze_runge_kutta(gauss6(), "irk");
  EXPECT_EQ(m.order, 6);
  EXPECT_EQ(m.stage_order, 3);
  EXPECT_TRUE(m.a_stable);
  EXPECT_FALSE(m.l_stable);
  EXPECT_NEAR(m.r_infinity, 1.0, 1e-12);
  const Polynomial p = {1, 0.5, 0.1, 1.0 / 120};
  ASSERT_EQ(m.p.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_NEAR(m.p[k], p[k], 1e-14) << k;
    EXPECT_NEAR(m.q[k], k % 2 ? -p[k] : p[k], 1e-14) << k;
  }
  EXPECT_EQ(m.dissipation_order, 0);
  EXPECT_EQ(m.dispersion_order, 7);
  // Order 6: the norms of orders 7 and 8 (48 and 115 trees) are both within the trees to 8.
  EXPECT_GT(m.error_norm_2, 0.0);
  EXPECT_GT(m.error_norm_2_next, 0.0);
}

TEST(MethodAnalysis, Sdirk3) {
  // Alexander (1977): order 3, stiffly accurate (b = last row), L-stable.
  const MethodAnalysis m = analyze_runge_kutta(sdirk3(), "dirk");
  EXPECT_EQ(m.order, 3);
  EXPECT_TRUE(m.stiffly_accurate);
  EXPECT_TRUE(m.a_stable);
  EXPECT_TRUE(m.l_stable);
  EXPECT_EQ(m.r_infinity, 0.0);
  // Q = (1 − γz)³ (the diagonal is γ).
  const double g = sdirk3().a(0, 0);
  ASSERT_EQ(m.q.size(), 4u);
  EXPECT_NEAR(m.q[1], -3 * g, 1e-14);
  EXPECT_NEAR(m.q[3], -g * g * g, 1e-14);
}

TEST(MethodAnalysis, FirstViolatedConditionAndValidate) {
  // Heun (2 stages, order 2) claiming 3: the first order-3 tree [t^2] has bᵀc² − 1/3 = 1/6.
  ButcherTableau heun = tableau("heun", 3, Mat{{0, 0}, {1, 0}}, Vec{{0.5, 0.5}});
  const auto conds = rk_order_conditions(heun, heun.b, 3);
  EXPECT_FALSE(first_violated_condition(conds, 2));
  const auto v = first_violated_condition(conds, 3);
  ASSERT_TRUE(v);
  EXPECT_EQ(v->name, "[t^2]");
  EXPECT_EQ(v->order, 3);
  EXPECT_NEAR(v->residual, 1.0 / 6, 1e-16);
  std::string message;
  try {
    heun.validate();
  } catch (const BadInput& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("order 3 claimed but the condition of tree [t^2] (order 3) has residual "
                         "0.167"),
            std::string::npos)
      << message;
  // A claim of 7 by gauss6 (order 6) is checked beyond the old limit of 6.
  ButcherTableau g = gauss6();
  g.order = 7;
  message.clear();
  try {
    g.validate();
  } catch (const BadInput& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("(order 7)"), std::string::npos) << message;
  g.order = 6;
  EXPECT_NO_THROW(g.validate());
}

// ---- Rosenbrock ---------------------------------------------------------------------------------

TEST(MethodAnalysis, RosenbrockRos3p) {
  // ROS3P (Lang & Verwer 2001): order 3, embedded 2, A-stable, R(∞) = 1 − √3 (their paper; the
  // transformed check is in tests/integrators/test_rosenbrock.cpp), stage order undefined.
  RosenbrockTableau r;
  r.name = "ros3p";
  r.order = 3;
  r.embedded_order = 2;
  const double g = 0.5 + std::sqrt(3.0) / 6.0;
  r.gamma = g;
  r.alpha = Mat{{0, 0, 0}, {1, 0, 0}, {1, 0, 0}};
  r.gamma_lower = Mat{{0, 0, 0}, {-1, 0, 0}, {-g, 0.5 - 2 * g, 0}};
  r.b = Vec{{2.0 / 3, 0, 1.0 / 3}};
  r.b_embedded = Vec{{1.0 / 3, 1.0 / 3, 1.0 / 3}};
  const MethodAnalysis m = analyze_rosenbrock(r);
  EXPECT_EQ(m.order, 3);
  EXPECT_EQ(m.embedded_order, 2);
  EXPECT_EQ(m.stage_order, -1);
  EXPECT_TRUE(m.a_stable);
  EXPECT_FALSE(m.l_stable);
  EXPECT_NEAR(m.r_infinity, std::sqrt(3.0) - 1, 1e-12);
  EXPECT_EQ(m.ssp_coefficient, -1.0);
}

// ROS34PW2 of Rang & Angermann (BIT 45, 2005, Table 4.2; the 16-digit values also in PETSc's
// TSROSWRA34PW2): 4 stages, order 3, a W-method of order 3 (the authors' design goal).
RosenbrockTableau ros34pw2() {
  RosenbrockTableau r;
  r.name = "ros34pw2";
  r.order = 3;
  const double g = 4.3586652150845900e-01;
  r.gamma = g;
  r.alpha = Mat{{0, 0, 0, 0},
                {8.7173304301691801e-01, 0, 0, 0},
                {8.4457060015369423e-01, -1.1299064236484185e-01, 0, 0},
                {0, 0, 1, 0}};
  r.gamma_lower = Mat{{0, 0, 0, 0},
                      {-8.7173304301691801e-01, 0, 0, 0},
                      {-9.0338057013044082e-01, 5.4180672388095326e-02, 0, 0},
                      {2.4212380706095346e-01, -1.2232505839045147e+00, 5.4526025533510214e-01, 0}};
  r.b = Vec{{2.4212380706095346e-01, -1.2232505839045147e+00, 1.5452602553351020e+00,
             4.3586652150845900e-01}};
  r.b_embedded = Vec{{3.7810903145819369e-01, -9.6042292212423178e-02, 5.0000000000000000e-01,
                      2.1793326075422950e-01}};
  r.embedded_order = 2;
  return r;
}

RosenbrockTableau ros3p_written() {  // Lang & Verwer (2001), as in RosenbrockRos3p
  RosenbrockTableau r;
  r.name = "ros3p";
  r.order = 3;
  const double g = 0.5 + std::sqrt(3.0) / 6.0;
  r.gamma = g;
  r.alpha = Mat{{0, 0, 0}, {1, 0, 0}, {1, 0, 0}};
  r.gamma_lower = Mat{{0, 0, 0}, {-1, 0, 0}, {-g, 0.5 - 2 * g, 0}};
  r.b = Vec{{2.0 / 3, 0, 1.0 / 3}};
  r.b_embedded = Vec{{1.0 / 3, 1.0 / 3, 1.0 / 3}};
  r.embedded_order = 2;
  return r;
}

// The W-conditions (an arbitrary matrix W in place of J; Steihaug & Wolfbrandt 1979) up to
// order 3, written out by hand from the W-method's B-series (Γ with its diagonal γ, 1 the vector
// of ones): bᵀ1 = 1; bᵀα1 = 1/2, bᵀΓ1 = 0; bᵀ(α1)² = 1/3, bᵀαα1 = 1/6, bᵀαΓ1 = 0, bᵀΓα1 = 0,
// bᵀΓΓ1 = 0. The trees: 1, 2, 5 of orders 1..3, and 13 of order 4 (counted by hand: [t^3];
// [t,[t]] and [t,W[t]]; [[t^2]] and W[[t^2]]; the 2³ colourings of the chain of three one-son
// vertices).
TEST(MethodAnalysis, WConditionsByHand) {
  std::vector<int> count(kMaxWOrder + 1, 0);
  for (const WTree& t : w_trees()) ++count[static_cast<std::size_t>(t.order)];
  EXPECT_EQ(count[1], 1);
  EXPECT_EQ(count[2], 2);
  EXPECT_EQ(count[3], 5);
  EXPECT_EQ(count[4], 13);
  for (const RosenbrockTableau& r : {ros34pw2(), ros3p_written()}) {
    const Index s = r.stages();
    const Mat al = r.alpha, ga = r.gamma_full();
    const Vec one = Vec::Ones(s), c = al * one;
    const std::map<std::string, double> expected = {{"t", r.b.sum() - 1.0},
                                                    {"[t]", r.b.dot(c) - 0.5},
                                                    {"W[t]", r.b.dot(ga * one)},
                                                    {"[t^2]", r.b.dot(c.cwiseProduct(c)) - 1.0 / 3},
                                                    {"[[t]]", r.b.dot(al * c) - 1.0 / 6},
                                                    {"[W[t]]", r.b.dot(al * ga * one)},
                                                    {"W[[t]]", r.b.dot(ga * c)},
                                                    {"W[W[t]]", r.b.dot(ga * ga * one)}};
    const auto conditions = rosenbrock_w_conditions(r, r.b, 3);
    ASSERT_EQ(conditions.size(), expected.size());
    for (const OrderCondition& k : conditions) {
      ASSERT_TRUE(expected.count(k.name)) << k.name;
      EXPECT_NEAR(k.residual, expected.at(k.name), 1e-14) << r.name << " " << k.name;
    }
  }
  // ROS34PW2: W-order 3 (Rang & Angermann 2005), classical order 3.
  const MethodAnalysis pw2 = analyze_rosenbrock(ros34pw2());
  EXPECT_EQ(pw2.order, 3);
  EXPECT_EQ(pw2.w_order, 3);
  EXPECT_EQ(pw2.embedded_order, 2);
  EXPECT_EQ(pw2.embedded_w_order, 2);
  // ROS3P: bᵀα1 = (2/3)·0 + 0·1 + (1/3)·1 = 1/3, not 1/2: W-order 1 (order 3 only with the exact
  // Jacobian, where bᵀΓ1 = 1/6 makes up bᵀβ1 = 1/2).
  const MethodAnalysis r3 = analyze_rosenbrock(ros3p_written());
  EXPECT_EQ(r3.order, 3);
  EXPECT_EQ(r3.w_order, 1);
  // ROS2 (Verwer et al. 1999): bᵀα1 = 1/2 and bᵀΓ1 = γ(b1 + b2) + b2·γ21 = γ − γ = 0, so W-order
  // 2 = its classical order (the W-order cannot exceed it).
  RosenbrockTableau ros2;
  ros2.name = "ros2";
  ros2.order = 2;
  ros2.gamma = 1 + 1 / std::sqrt(2.0);
  ros2.alpha = Mat{{0, 0}, {1, 0}};
  ros2.gamma_lower = Mat{{0, 0}, {-2 * ros2.gamma, 0}};
  ros2.b = Vec{{0.5, 0.5}};
  const MethodAnalysis m2 = analyze_rosenbrock(ros2);
  EXPECT_EQ(m2.order, 2);
  EXPECT_EQ(m2.w_order, 2);
  EXPECT_EQ(m2.embedded_w_order, 0);
  // Other kinds have none.
  EXPECT_EQ(analyze_runge_kutta(rk4(), "explicit_rk").w_order, -1);
}

// The embedded formula's stability function R̂ = P̂/Q̂, against direct evaluations of
// R̂(z) = 1 + z b̂ᵀ(I − zM)⁻¹1 (M = A for Runge–Kutta, α + Γ for Rosenbrock; Hairer & Wanner II,
// IV.7) with Eigen: |R̂(∞)| as 1 − b̂ᵀM⁻¹1 where M is invertible (rodas4), else R̂ at z = −1e9
// (esdirk43, whose A has a zero first row); A-stability against samples of |R̂(iy)|; the axis
// limits of an explicit pair by evaluation just inside and outside.
TEST(MethodAnalysis, EmbeddedFormulaStability) {
  using cd = std::complex<double>;
  const auto r_hat = [](const Mat& m, const Vec& w, cd z) {
    const Index s = w.size();
    const Eigen::MatrixXcd lhs = Eigen::MatrixXcd::Identity(s, s) - z * m.cast<cd>();
    const Eigen::VectorXcd k = lhs.partialPivLu().solve(Eigen::VectorXcd::Ones(s));
    return 1.0 + z * w.cast<cd>().dot(k);
  };
  const auto max_on_imaginary_axis = [&](const Mat& m, const Vec& w) {
    double worst = 0;
    for (int k = 0; k <= 4000; ++k)
      worst =
          std::max(worst, std::abs(r_hat(m, w, cd(0.0, std::pow(10.0, -3.0 + 9.0 * k / 4000)))));
    return worst;
  };
  {
    const auto integ = testing_support::make("rodas4");
    const RosenbrockTableau& r = *integ->rosenbrock_tableau();
    const Mat m = r.alpha + r.gamma_full();
    const double r_inf = 1.0 - r.b_embedded.dot(m.fullPivLu().solve(Vec::Ones(r.stages())));
    const MethodAnalysis a = analyze_rosenbrock(r);
    ASSERT_TRUE(a.embedded_stability);
    EXPECT_NEAR(a.embedded_stability->r_infinity, std::abs(r_inf), 1e-12);
    EXPECT_EQ(a.embedded_stability->a_stable, max_on_imaginary_axis(m, r.b_embedded) <= 1 + 1e-12);
    EXPECT_EQ(a.embedded_stability->l_stable,
              a.embedded_stability->a_stable && std::abs(r_inf) <= 1e-12);
  }
  {
    const auto integ = testing_support::make("esdirk43");
    const ButcherTableau& t = *integ->butcher_tableau();
    const double r_inf = std::abs(r_hat(t.a, t.b_embedded, cd(-1e9, 0.0)));
    const MethodAnalysis a = analyze_runge_kutta(t, "dirk");
    ASSERT_TRUE(a.embedded_stability);
    EXPECT_NEAR(a.embedded_stability->r_infinity, r_inf, 1e-7);
    EXPECT_EQ(a.embedded_stability->a_stable,
              max_on_imaginary_axis(t.a, t.b_embedded) <= 1 + 1e-12);
  }
  {
    const auto integ = testing_support::make("dopri5");
    const ButcherTableau& t = *integ->butcher_tableau();
    const MethodAnalysis a = analyze_runge_kutta(t, "explicit_rk");
    ASSERT_TRUE(a.embedded_stability);
    const auto& e = *a.embedded_stability;
    EXPECT_TRUE(std::isinf(e.r_infinity));
    EXPECT_FALSE(e.a_stable);
    ASSERT_FALSE(e.real_axis_unbounded);
    EXPECT_LE(std::abs(r_hat(t.a, t.b_embedded, cd(-e.real_axis_limit * (1 - 1e-6), 0))), 1.0);
    EXPECT_GT(std::abs(r_hat(t.a, t.b_embedded, cd(-e.real_axis_limit * (1 + 1e-6), 0))), 1.0);
    if (e.imag_axis_limit > 0) {
      EXPECT_LE(std::abs(r_hat(t.a, t.b_embedded, cd(0, e.imag_axis_limit * (1 - 1e-6)))), 1.0);
      EXPECT_GT(std::abs(r_hat(t.a, t.b_embedded, cd(0, e.imag_axis_limit * (1 + 1e-6)))), 1.0);
    }
    // The main formula's limits differ from the embedded one's (different weights).
    EXPECT_NE(a.real_axis_limit, e.real_axis_limit);
  }
  // No embedded weights: no embedded figures.
  EXPECT_FALSE(analyze_runge_kutta(rk4(), "explicit_rk").embedded_stability);
}

// ROS3P's embedded weights give the same stability function as its own (Lang & Verwer 2001
// chose them so): checked here without the polynomial forms, by one step of the scalar
// Rosenbrock recursion on y' = λy, (1 − γz) k_i = z (1 + Σ_j α_ij k_j) + z Σ_j γ_ij k_j with
// z = hλ, y1 = 1 + bᵀk against ŷ1 = 1 + b̂ᵀk, at points across the plane. Every other built-in
// pair with embedded weights has a different R̂ and no such note (ros3p is the one whose estimate
// vanishes on heat_2d, docs/commands/work-precision.md).
TEST(MethodAnalysis, EmbeddedWeightsWithTheSameStabilityFunctionAreNamed) {
  const auto ros3p = testing_support::make("ros3p");
  const RosenbrockTableau& r = *ros3p->rosenbrock_tableau();
  const Index s = r.stages();
  for (const std::complex<double> z : {std::complex<double>(-0.7, 0.0), {0.3, 1.3}, {-5.0, 2.0}}) {
    std::vector<std::complex<double>> k(static_cast<std::size_t>(s));
    std::complex<double> y1 = 1.0, y1_hat = 1.0;
    for (Index i = 0; i < s; ++i) {
      std::complex<double> arg = 1.0, lower = 0.0;
      for (Index j = 0; j < i; ++j) {
        arg += r.alpha(i, j) * k[static_cast<std::size_t>(j)];
        lower += r.gamma_lower(i, j) * k[static_cast<std::size_t>(j)];
      }
      k[static_cast<std::size_t>(i)] = (z * arg + z * lower) / (1.0 - r.gamma * z);
      y1 += r.b[i] * k[static_cast<std::size_t>(i)];
      y1_hat += r.b_embedded[i] * k[static_cast<std::size_t>(i)];
    }
    EXPECT_LT(std::abs(y1 - y1_hat), 1e-14 * std::abs(y1)) << z;
  }
  const MethodAnalysis m = analyze_rosenbrock(r);
  EXPECT_TRUE(m.embedded_same_stability);
  bool noted = false;
  for (const auto& n : m.notes) noted = noted || n.find("same stability function") != n.npos;
  EXPECT_TRUE(noted);

  int pairs = 0;
  for (const auto& e : integrator_registry().entries()) {
    if (e.info.name == "ros3p") continue;
    const auto integ = testing_support::make(e.info.name);
    std::optional<MethodAnalysis> a;
    if (const ButcherTableau* t = integ->butcher_tableau(); t && t->b_embedded.size() > 0)
      a = analyze_runge_kutta(*t, t->is_explicit() ? "explicit_rk" : "irk");
    else if (const RosenbrockTableau* q = integ->rosenbrock_tableau(); q && q->b_embedded.size())
      a = analyze_rosenbrock(*q);
    if (!a) continue;
    ++pairs;
    EXPECT_FALSE(a->embedded_same_stability) << e.info.name;
  }
  EXPECT_GE(pairs, 7);  // bs3, cash_karp, dopri5, rkf45, esdirk43, trbdf2, rodas4
}

// ---- Kick/drift splittings ----------------------------------------------------------------------

KickDriftCoefficients verlet_composition(std::string name, int order,
                                         const std::vector<double>& gamma) {
  // γ_j-steps of velocity Verlet (kick ½γ, drift γ, kick ½γ), adjacent kicks merged.
  KickDriftCoefficients c{std::move(name), std::vector<double>(gamma.size() + 1, 0.0),
                          std::vector<double>(gamma.size() + 1, 0.0), order};
  for (std::size_t j = 0; j < gamma.size(); ++j) {
    c.kick[j] += 0.5 * gamma[j];
    c.kick[j + 1] += 0.5 * gamma[j];
    c.drift[j] = gamma[j];
  }
  return c;
}

TEST(MethodAnalysis, SplittingOrders) {
  // Orders from the literature: symplectic Euler 1, velocity Verlet 2 (Hairer, Lubich & Wanner
  // 2006, §II.5), the triple jump 4 (Yoshida 1990, c = 1/(2 − 2^(1/3))), Yoshida's solution A
  // 6, Blanes & Moan (2002) SRKN_6^b 4 (for x'' = a(x)).
  const MethodAnalysis euler = analyze_kick_drift({"symplectic_euler", {1.0}, {1.0}, 1});
  EXPECT_EQ(euler.order, 1);
  const MethodAnalysis verlet = analyze_kick_drift({"velocity_verlet", {0.5, 0.5}, {1.0, 0.0}, 2});
  EXPECT_EQ(verlet.order, 2);
  // log(e^{B/2} e^{A} e^{B/2}) = A + B − [A,[A,B]]/24 − [B,[A,B]]/12 + O(5) (BCH, HLW §III.4):
  // the largest word coefficient of degree 3 is 2/12 (the word BAB).
  EXPECT_NEAR(verlet.residual_by_order[2], 1.0 / 6, 1e-15);
  EXPECT_NEAR(verlet.residual_by_order[3], 0.0, 1e-15);  // symmetric: no even-degree terms
  // Oscillator: the half-trace of Verlet's step map on x'' = −ω²x is 1 − (hω)²/2: hω < 2.
  EXPECT_NEAR(verlet.oscillator_limit, 2.0, 1e-12);
  const double c = 1.0 / (2.0 - std::cbrt(2.0));
  EXPECT_EQ(analyze_kick_drift(verlet_composition("yoshida4", 4, {c, 1 - 2 * c, c})).order, 4);
  // The triple jump with a perturbed c keeps only the symmetric order 2.
  const double d = c + 1e-3;
  EXPECT_EQ(analyze_kick_drift(verlet_composition("bad", 4, {d, 1 - 2 * d, d})).order, 2);
  const double w1 = -1.17767998417887, w2 = 0.235573213359357, w3 = 0.784513610477560;
  const double w0 = 1.0 - 2.0 * (w1 + w2 + w3);
  const MethodAnalysis y6 =
      analyze_kick_drift(verlet_composition("yoshida6", 6, {w3, w2, w1, w0, w1, w2, w3}));
  EXPECT_EQ(y6.order, 6);
  const double b1 = 0.0829844064174052, b2 = 0.396309801498368, b3 = -0.0390563049223486;
  const double b4 = 1.0 - 2.0 * (b1 + b2 + b3);
  const double a1 = 0.245298957184271, a2 = 0.604872665711080, a3 = 0.5 - (a1 + a2);
  const MethodAnalysis bm = analyze_kick_drift(
      {"blanes_moan", {b1, b2, b3, b4, b3, b2, b1}, {a1, a2, a3, a3, a2, a1, 0.0}, 4});
  EXPECT_EQ(bm.order, 4);
  EXPECT_TRUE(bm.p.empty());
}

// ---- Every registered coefficient method -------------------------------------------------------

TEST(MethodAnalysis, RegistryClaimsAgreeWithTheAnalysis) {
  // The orders the registry claims come from the literature (MethodInfo::order); the analysis
  // derives them from the coefficients alone. Every method with coefficients must agree, and
  // its exact A-stability must match the one of its LinearStability (core/linear_stability).
  int analysed = 0;
  for (const auto& e : integrator_registry().entries()) {
    const auto integ = testing_support::make(e.info.name);
    std::optional<MethodAnalysis> m;
    if (const ButcherTableau* t = integ->butcher_tableau())
      m = analyze_runge_kutta(*t, t->is_explicit() ? "explicit_rk" : "irk");
    else if (const RosenbrockTableau* r = integ->rosenbrock_tableau())
      m = analyze_rosenbrock(*r);
    else if (const KickDriftCoefficients* k = integ->kick_drift_coefficients())
      m = analyze_kick_drift(*k);
    if (!m) continue;
    ++analysed;
    EXPECT_EQ(m->order, e.info.order) << e.info.name;
    if (const auto s = integ->linear_stability(); s && s->rational) {
      EXPECT_EQ(m->a_stable, a_stable_exact(*s).value_or(false)) << e.info.name;
    }
  }
  EXPECT_GE(analysed, 20);
}

}  // namespace
}  // namespace stiffbench

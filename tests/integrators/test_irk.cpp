// Fully implicit Runge–Kutta methods built from their tableau (ImplicitRungeKutta, and Radau5
// from a tableau; integrators/implicit/gauss.hpp, radau5.hpp). Expected numbers come from theory
// (the classical order of each tableau, seen as the slope of the global error against the exact
// solution over a step ladder; the structure of A⁻¹) or from a second implementation of the same
// method (radau5's own stepper against the generic one).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/driver.hpp"
#include "integrators/implicit/gauss.hpp"
#include "integrators/implicit/radau5.hpp"
#include "integrators/solvers/linear_solver.hpp"
#include "integrators/solvers/newton.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

ButcherTableau tableau(std::string name, int order, Mat a, Vec b, Vec c) {
  ButcherTableau t;
  t.name = std::move(name);
  t.order = order;
  t.a = std::move(a);
  t.b = std::move(b);
  t.c = std::move(c);
  return t;
}

// Radau IIA, 3 stages, order 5 (Hairer & Wanner II, Table IV.5.6).
ButcherTableau radau_iia3() {
  const double r = std::sqrt(6.0);
  return tableau("radau_iia3", 5,
                 Mat{{(88 - 7 * r) / 360, (296 - 169 * r) / 1800, (-2 + 3 * r) / 225},
                     {(296 + 169 * r) / 1800, (88 + 7 * r) / 360, (-2 - 3 * r) / 225},
                     {(16 - r) / 36, (16 + r) / 36, 1.0 / 9}},
                 Vec{{(16 - r) / 36, (16 + r) / 36, 1.0 / 9}},
                 Vec{{(4 - r) / 10, (4 + r) / 10, 1.0}});
}

// Lobatto IIIC, 3 stages, order 4 (Hairer & Wanner II, §IV.5, Table 5.11): stiffly accurate,
// c_1 = 0 (a node at 0: the starting values interpolate the stages without q(0) = 0).
ButcherTableau lobatto_iiic3() {
  return tableau("lobatto_iiic3", 4,
                 Mat{{1.0 / 6, -1.0 / 3, 1.0 / 6},
                     {1.0 / 6, 5.0 / 12, -1.0 / 12},
                     {1.0 / 6, 2.0 / 3, 1.0 / 6}},
                 Vec{{1.0 / 6, 2.0 / 3, 1.0 / 6}}, Vec{{0.0, 0.5, 1.0}});
}

// Gauss–Legendre, 2 stages, order 4 (Hairer, Nørsett & Wanner I, §II.7), typed here.
ButcherTableau gauss2() {
  const double r = std::sqrt(3.0) / 6;
  return tableau("my_gauss2", 4, Mat{{0.25, 0.25 - r}, {0.25 + r, 0.25}}, Vec{{0.5, 0.5}},
                 Vec{{0.5 - r, 0.5 + r}});
}

// Lobatto IIIA, 3 stages, order 4 (Hairer & Wanner II, Table IV.5.7): first row of A zero.
ButcherTableau lobatto_iiia3() {
  return tableau("lobatto_iiia3", 4,
                 Mat{{0.0, 0.0, 0.0}, {5.0 / 24, 1.0 / 3, -1.0 / 24}, {1.0 / 6, 2.0 / 3, 1.0 / 6}},
                 Vec{{1.0 / 6, 2.0 / 3, 1.0 / 6}}, Vec{{0.0, 0.5, 1.0}});
}

// Max-norm error at t = 5 on Kepler (e = 0.5, exact solution by Kepler's equation) for each
// step of the ladder h = h0 / 2^k, k = 0..levels-1, and the least-squares slope of log(error)
// against log(h).
struct Ladder {
  std::vector<double> h, error;
  double slope = 0.0;
};

Ladder kepler_ladder(Integrator& integ, double h0, int levels) {
  const auto sys = model("kepler", {"e=0.5"});
  Vec exact(sys->dimension());
  sys->exact(5.0, exact);
  Ladder l;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (int k = 0; k < levels; ++k) {
    FixedStepOptions opt;
    opt.t_end = 5.0;
    opt.h = h0 / std::pow(2.0, k);
    const RunResult r = run_fixed_step(*sys, integ, opt);
    EXPECT_EQ(r.stats.status, Status::ok)
        << integ.info().name << " h = " << opt.h << ": " << r.stats.message;
    l.h.push_back(r.h);
    l.error.push_back((r.y - exact).cwiseAbs().maxCoeff());
    const double x = std::log(r.h), y = std::log(l.error.back());
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  const double n = levels;
  l.slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  return l;
}

// The classical order of each tableau appears as the slope of the global error against the
// exact solution on a smooth, non-stiff problem (Kepler e = 0.5 to t = 5, h = h0/2^k; measured:
// radau_iia3 from h0 = 0.04, 4 levels: 7.1e-7 … 2.2e-11, slope 5.00; my_gauss2 from 0.04:
// 9.3e-6 … 2.3e-9, slope 4.00, the registered gauss4's errors; lobatto_iiic3, whose errors
// reach the asymptotic ratio 16 later (14.6, 15.3, 15.7 from h = 0.02), from 0.01, 3 levels:
// 5.1e-8 … 2.1e-10, slope 3.96).
TEST(ImplicitRungeKutta, ReachesTheOrderOfItsTableauOnKepler) {
  struct Case {
    ButcherTableau t;
    double h0;
    int levels;
  };
  for (const auto& [t, h0, levels] :
       {Case{radau_iia3(), 0.04, 4}, Case{lobatto_iiic3(), 0.01, 3}, Case{gauss2(), 0.04, 4}}) {
    SCOPED_TRACE(t.name);
    ImplicitRungeKutta integ(t, "test", {});
    EXPECT_EQ(integ.info().name, t.name);
    EXPECT_EQ(integ.info().order, t.order);
    EXPECT_EQ(integ.info().stages, t.stages());
    EXPECT_EQ(integ.info().family, Family::implicit);
    ASSERT_NE(integ.butcher_tableau(), nullptr);
    EXPECT_EQ(integ.butcher_tableau()->a, t.a);
    const Ladder l = kepler_ladder(integ, h0, levels);
    EXPECT_NEAR(l.slope, t.order, 0.1) << "errors " << l.error[0] << " ... " << l.error.back();
    // Above round-off (max ‖y‖ ~ 3 on this orbit): the slope measures the method.
    EXPECT_GT(l.error.back(), 1e-13);
  }
}

// The transformation: A⁻¹ of each 3-stage tableau has one real eigenvalue and one complex pair
// (the real root and the pair of det(I - zA) = Q(z), the denominator of R), Gauss 2 one pair
// 3 ± i√3 (A⁻¹ has trace 6 and determinant 12). T⁻¹A⁻¹T is Λ's blocks to round-off and
// dᵀA = bᵀ. For the stiffly accurate tableaux d = e_s (y_{n+1} is the last stage).
TEST(ImplicitRungeKutta, TransformationFromTheTableau) {
  for (const ButcherTableau& t : {radau_iia3(), lobatto_iiic3(), gauss2()}) {
    SCOPED_TRACE(t.name);
    const IrkConstants k = irk_constants(t);
    const Index s = t.stages();
    EXPECT_EQ(k.real.size(), s == 3 ? 1u : 0u);
    ASSERT_EQ(k.a.size(), 1u);
    Mat expected = Mat::Zero(s, s);
    Index j = 0;
    for (double g : k.real) expected(j, j) = g, ++j;
    expected(j, j) = expected(j + 1, j + 1) = k.a[0];
    expected(j, j + 1) = k.b[0];
    expected(j + 1, j) = -k.b[0];
    EXPECT_LE((k.t_inv * t.a.inverse() * k.t - expected).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((k.d.transpose() * t.a - t.b.transpose()).cwiseAbs().maxCoeff(), 1e-14);
    if (s == 3) {
      EXPECT_LE((k.d - Vec::Unit(3, 2)).cwiseAbs().maxCoeff(), 1e-13);
    }
  }
  const IrkConstants g = irk_constants(gauss2());
  EXPECT_NEAR(g.a[0], 3.0, 1e-13);
  EXPECT_NEAR(std::abs(g.b[0]), std::sqrt(3.0), 1e-13);
  // Lobatto IIIC: Q(z) = 1 - 3z/4 + z²/4 - z³/24 (the (1,3) Padé denominator, HW II Table
  // IV.5.11's R), so A⁻¹'s eigenvalues are the roots of z³ - 6z² + 18z - 24: their sum is 6 and
  // product 24.
  const IrkConstants l = irk_constants(lobatto_iiic3());
  EXPECT_NEAR(l.real[0] + 2 * l.a[0], 6.0, 1e-12);
  EXPECT_NEAR(l.real[0] * (l.a[0] * l.a[0] + l.b[0] * l.b[0]), 24.0, 1e-11);
}

// The same Radau IIA method by two implementations: the generic stepper from the tableau and
// radau5's own (fixed step, both iterating Newton to round-off) agree to round-off on HIRES
// (stiff, h = 0.05 to t = 2; measured: largest relative difference 5.9e-15, 167 Newton
// iterations each).
TEST(ImplicitRungeKutta, RadauIIAAgreesWithRadau5) {
  const auto sys = model("hires");
  ImplicitRungeKutta irk(radau_iia3(), "test", {});
  const auto r5 = make("radau5");
  FixedStepOptions opt;
  opt.t_end = 2.0;
  opt.h = 0.05;
  const RunResult a = run_fixed_step(*sys, irk, opt);
  const RunResult b = run_fixed_step(*sys, *r5, opt);
  ASSERT_EQ(a.stats.status, Status::ok) << a.stats.message;
  ASSERT_EQ(b.stats.status, Status::ok) << b.stats.message;
  const double rel = ((a.y - b.y).array().abs() / b.y.array().abs().max(1e-300)).maxCoeff();
  EXPECT_LE(rel, 1e-12);
}

// Every linear-solver option of the family: dense and sparse LU factor the same transformed
// systems, so the runs agree to round-off (Lobatto IIIC on heat_2d with 100 unknowns, h = 0.01
// to t = 0.1; measured: max-norm difference 7.5e-15 of max |y|).
TEST(ImplicitRungeKutta, DenseAndSparseLuAgree) {
  const auto sys = model("heat_2d", {"n=10"});
  GaussOptions dense, sparse;
  dense.linear = LinearSolverKind::dense_lu;
  sparse.linear = LinearSolverKind::sparse_lu;
  ImplicitRungeKutta a_integ(lobatto_iiic3(), "test", dense);
  ImplicitRungeKutta b_integ(lobatto_iiic3(), "test", sparse);
  FixedStepOptions opt;
  opt.t_end = 0.1;
  opt.h = 0.01;
  const RunResult a = run_fixed_step(*sys, a_integ, opt);
  const RunResult b = run_fixed_step(*sys, b_integ, opt);
  ASSERT_EQ(a.stats.status, Status::ok) << a.stats.message;
  ASSERT_EQ(b.stats.status, Status::ok) << b.stats.message;
  const double rel = (a.y - b.y).cwiseAbs().maxCoeff() / b.y.cwiseAbs().maxCoeff();
  EXPECT_LE(rel, 1e-12);
}

// A singular A (Lobatto IIIA's first row is zero) is bad input naming the tableau, before any
// run; so is an A⁻¹ without a full set of eigenvectors (an SDIRK's A⁻¹ is one 2×2 Jordan block
// for the double eigenvalue 1/γ).
TEST(ImplicitRungeKutta, SingularOrDefectiveAIsBadInput) {
  try {
    ImplicitRungeKutta integ(lobatto_iiia3(), "test", {});
    FAIL() << "built from a singular A";
  } catch (const BadInput& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("tableau 'lobatto_iiia3'"), std::string::npos) << m;
    EXPECT_NE(m.find("A is singular (row 0 of A is zero)"), std::string::npos) << m;
  }
  const double g = 1 - std::sqrt(0.5);
  try {
    ImplicitRungeKutta integ(
        tableau("sdirk2_as_irk", 2, Mat{{g, 0.0}, {1 - g, g}}, Vec{{1 - g, g}}, Vec{{g, 1.0}}),
        "test", {});
    FAIL() << "built from a defective A^-1";
  } catch (const BadInput& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("tableau 'sdirk2_as_irk'"), std::string::npos) << m;
    EXPECT_NE(m.find("A^-1 has a repeated eigenvalue without a full set of eigenvectors"),
              std::string::npos)
        << m;
  }
  // The tableau's own claims are checked too (ButcherTableau::validate): order 5 is not met by
  // Lobatto IIIC.
  ButcherTableau over = lobatto_iiic3();
  over.order = 5;
  EXPECT_THROW(ImplicitRungeKutta(over, "test", {}), BadInput);
}

// --- Radau5 from a tableau ----------------------------------------------------------------

// Radau5 derives everything from the tableau it is given, whatever its name: the built-in
// radau5's tableau under another name gives bitwise the same results as the registered radau5
// (fixed step and adaptive on HIRES; the registered radau5 itself was checked unchanged by this
// change with scripts/compare_csv.py over convergence runs on kepler, hires, van_der_pol and
// heat_2d).
TEST(Radau5FromTableau, SameTableauGivesBitwiseTheSameRun) {
  ButcherTableau t = radau5_tableau();
  t.name = "my_radau";
  const auto sys = model("hires");
  for (const bool adaptive : {false, true}) {
    SCOPED_TRACE(adaptive ? "adaptive" : "fixed step");
    Radau5Options o;
    o.control.rtol = 1e-6;
    o.control.atol = 1e-8;
    Radau5 mine(t, o);
    const auto builtin = make("radau5", {"rtol=1e-6", "atol=1e-8"});
    EXPECT_EQ(mine.info().name, "my_radau");
    RunResult a, b;
    if (adaptive) {
      AdaptiveOptions opt;
      opt.t_end = 10.0;
      a = run_adaptive(*sys, mine, opt);
      b = run_adaptive(*sys, *builtin, opt);
    } else {
      FixedStepOptions opt;
      opt.t_end = 2.0;
      opt.h = 0.1;
      a = run_fixed_step(*sys, mine, opt);
      b = run_fixed_step(*sys, *builtin, opt);
    }
    ASSERT_EQ(a.stats.status, Status::ok) << a.stats.message;
    ASSERT_EQ(b.stats.status, Status::ok) << b.stats.message;
    for (Index i = 0; i < a.y.size(); ++i) EXPECT_EQ(a.y[i], b.y[i]) << i;
    EXPECT_EQ(a.stats.f_evals, b.stats.f_evals);
    EXPECT_EQ(a.stats.newton_iters, b.stats.newton_iters);
    EXPECT_EQ(a.stats.steps, b.stats.steps);
  }
}

// RADAU5's machinery on another stiffly accurate 3-stage tableau with c_3 = 1: Lobatto IIIC
// (a node at 0) reaches its order 4 in fixed steps on Kepler (exact solution; h = 0.01/2^k,
// k = 0..2, as above; measured: the generic stepper's errors to 3 digits).
TEST(Radau5FromTableau, LobattoIIICReachesOrderFour) {
  Radau5 integ(lobatto_iiic3(), {});
  EXPECT_EQ(integ.info().order, 4);
  EXPECT_NE(integ.info().description.find("'lobatto_iiic3'"), std::string::npos);
  ASSERT_NE(integ.butcher_tableau(), nullptr);
  const Ladder l = kepler_ladder(integ, 0.01, 3);
  EXPECT_NEAR(l.slope, 4.0, 0.1) << "errors " << l.error[0] << " ... " << l.error.back();
}

// What RADAU5 relies on is checked, naming the tableau: 3 stages, c_3 = 1 and b the last row of
// A (Gauss 3 has neither), an invertible A.
TEST(Radau5FromTableau, StructureIsCheckedNamingTheTableau) {
  const auto message = [](const ButcherTableau& t) {
    try {
      Radau5 integ(t, {});
    } catch (const BadInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message(gauss2()), "tableau 'my_gauss2': RADAU5 needs 3 stages (it has 2)");
  const std::string g3 = message(gauss_tableau(3));
  EXPECT_NE(g3.find("tableau 'gauss6': RADAU5 needs c_3 = 1"), std::string::npos) << g3;
  ButcherTableau moved = radau_iia3();
  moved.b = Vec{{0.3, 0.3, 0.4}};  // c_3 = 1 still, not stiffly accurate (and not order 5)
  moved.order = 1;
  const std::string sa = message(moved);
  EXPECT_NE(sa.find("tableau 'radau_iia3': RADAU5 needs a stiffly accurate tableau"),
            std::string::npos)
      << sa;
  const std::string la = message(lobatto_iiia3());
  EXPECT_NE(la.find("tableau 'lobatto_iiia3': RADAU5 needs an invertible A"), std::string::npos)
      << la;
}

}  // namespace
}  // namespace stiffbench

namespace stiffbench {
namespace {

// `linear_solver=auto` between dense and sparse LU (automatic_is_dense): dense up to 50
// unknowns, and up to 200 unless the Jacobian's pattern fills under 10%. The Brusselator with
// diffusion at N = 100 (200 interleaved unknowns) has 4 nonzeros in each row but the 4 boundary
// rows (u_i: u_{i-1}, u_i, u_{i+1}, v_i; v_i: u_i, v_{i-1}, v_i, v_{i+1}; Hairer & Wanner II
// §IV.1): 8N - 4 = 796 of 200², density 0.0199, so auto is sparse — radau5's auto run is then
// bit for bit its sparse_lu run, and its dense_lu run agrees to round-off.
// HIRES (8 unknowns) stays dense whatever its pattern.
TEST(ImplicitRungeKutta, AutomaticLinearSolverFollowsThePatternDensity) {
  const auto bruss = testing_support::model("brusselator", {"n=100"});
  LinearSolverOptions o;
  const double density = jacobian_pattern_density(*bruss, o);
  EXPECT_DOUBLE_EQ(density, 796.0 / (200.0 * 200.0));
  o.pattern_density = density;
  EXPECT_FALSE(automatic_is_dense(o, 200));
  EXPECT_TRUE(automatic_is_dense(o, 50));
  o.pattern_density = 1.0;
  EXPECT_TRUE(automatic_is_dense(o, 200));
  EXPECT_FALSE(automatic_is_dense(o, 201));
  const auto hires = testing_support::model("hires");
  EXPECT_DOUBLE_EQ(jacobian_pattern_density(*hires, LinearSolverOptions{}), 1.0);  // n <= 50

  FixedStepOptions opt;
  opt.t_end = 0.02;
  opt.h = 0.01;
  const auto run = [&](const std::string& ls) {
    const auto r5 = testing_support::make("radau5", {"linear_solver=" + ls});
    const RunResult r = run_fixed_step(*bruss, *r5, opt);
    EXPECT_EQ(r.stats.status, Status::ok) << ls << ": " << r.stats.message;
    return r.y;
  };
  const Vec automatic = run("auto"), sparse = run("sparse_lu"), dense = run("dense_lu");
  EXPECT_EQ((automatic - sparse).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((automatic - dense).cwiseAbs().maxCoeff(), 1e-12 * dense.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace stiffbench

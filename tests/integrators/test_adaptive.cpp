// The shared step-size controller and the methods that use it (integrators/adaptive/): embedded
// explicit pairs and Radau IIA. Expected numbers come from theory (order conditions, the
// evaluation counts each header derives, tolerance proportionality) or from exact solutions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "core/driver.hpp"
#include "experiments/studies/convergence.hpp"
#include "integrators/adaptive/controller.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "integrators/implicit/radau5.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

// --- embedded tableaux --------------------------------------------------------------------

class EmbeddedTableauTest : public ::testing::TestWithParam<ButcherTableau> {};

// Both weight rows meet every order condition (rooted trees, Butcher) up to their claimed order
// and miss one of the next order: the coefficients typed in tableaux.cpp are checked here, not
// trusted.
TEST_P(EmbeddedTableauTest, OrderConditionsOfBothRows) {
  const ButcherTableau& t = GetParam();
  EXPECT_LE(t.row_sum_defect(), 1e-15);
  ASSERT_EQ(t.b_embedded.size(), t.b.size());
  for (int p = 1; p <= t.order; ++p) EXPECT_LE(t.order_defect(t.b, p), 1e-14) << "b, p = " << p;
  EXPECT_GT(t.order_defect(t.b, t.order + 1), 1e-6);
  for (int p = 1; p <= t.embedded_order; ++p)
    EXPECT_LE(t.order_defect(t.b_embedded, p), 1e-14) << "b_embedded, p = " << p;
  EXPECT_GT(t.order_defect(t.b_embedded, t.embedded_order + 1), 1e-6);
}

// FSAL: the last stage is evaluated at y⁺ (c_s = 1, last row of A = b), so it is f(t + h, y⁺).
TEST_P(EmbeddedTableauTest, FsalStructure) {
  const ButcherTableau& t = GetParam();
  const Index s = t.stages();
  const bool last_row_is_b = (t.a.row(s - 1).transpose() - t.b).cwiseAbs().maxCoeff() == 0.0;
  EXPECT_EQ(t.fsal, last_row_is_b && std::abs(t.c[s - 1] - 1.0) <= 1e-15 && t.b[s - 1] == 0.0)
      << t.name;
}

INSTANTIATE_TEST_SUITE_P(Embedded, EmbeddedTableauTest, ::testing::ValuesIn(embedded_tableaux()),
                         [](const auto& param_info) { return param_info.param.name; });

// --- fixed-step orders --------------------------------------------------------------------

// Observed global order on the eccentric Kepler orbit (e = 0.5, exact solution), fixed steps.
// The propagated solution sets the order: bs3 3, dopri5 5, cash_karp 5 (it propagates the
// fifth-order row), rkf45 4 (Fehlberg propagates the fourth-order row). The ladders keep the
// errors between ~1e-4 and ~1e-11 (asymptotic, far above round-off).
TEST(AdaptiveFixedStep, ObservedOrdersOnKepler) {
  const std::vector<std::tuple<std::string, double, int>> cases = {
      {"bs3", 0.01, 3}, {"dopri5", 0.04, 5}, {"cash_karp", 0.04, 5}, {"rkf45", 0.02, 4}};
  for (const auto& [name, h, order] : cases) {
    ConvergenceSpec spec;
    spec.model = "kepler";
    spec.params = Params::from_assignments({"e=0.5"});
    spec.integrators = {name};
    spec.t_end = 5;
    spec.h = h;
    spec.levels = name == "rkf45" ? 5 : 4;  // rkf45's fifth-order term fades slowly (4.09 last)
    const auto res = run_convergence(spec, nullptr);
    const auto p = last_observed_order(res.rows, name);
    ASSERT_TRUE(p.has_value()) << name;
    EXPECT_NEAR(*p, order, 0.2) << name;
    EXPECT_EQ(integrator_registry().at(name).info.order, order);
  }
}

// Fixed-step evaluation counts: an FSAL pair pays f(t0, y0) once and s - 1 per step; the others
// s per step.
TEST(AdaptiveFixedStep, EvaluationCounts) {
  auto sys = model("kepler");
  for (const auto& t : embedded_tableaux()) {
    auto integ = make(t.name);
    FixedStepOptions opt;
    opt.t_end = 1.0;
    opt.h = 0.01;
    const RunResult r = run_fixed_step(*sys, *integ, opt);
    const long s = t.stages();
    EXPECT_EQ(r.stats.f_evals, t.fsal ? 1 + 100 * (s - 1) : 100 * s) << t.name;
    EXPECT_EQ(integ->info().stages, t.fsal ? s - 1 : s) << t.name;
  }
}

// --- adaptive mode ------------------------------------------------------------------------

double error_vs_exact(const OdeSystem& sys, const RunResult& r) {
  Vec exact(sys.dimension());
  sys.exact(r.t, exact);
  return (r.y - exact).cwiseAbs().maxCoeff();
}

// Tolerance proportionality (HNW I §II.4): with local extrapolation the step is set by the
// fourth-order estimate, h ∝ tol^(1/5), and the fifth-order global error ∝ h^5 ∝ tol: slope 1
// of log(error) against log(rtol), fitted by least squares over rtol = 1e-4 .. 1e-10 (atol =
// rtol, output only at t_end). Measured 0.91: the pairwise slopes steepen from 0.55 (1e-4 →
// 1e-5, steps too large for the asymptotic regime) to 1.06 (1e-9 → 1e-10).
TEST(AdaptiveDopri5, GlobalErrorProportionalToTolerance) {
  auto sys = model("kepler", {"e=0.5"});
  std::vector<double> lx, ly;
  for (int k = 4; k <= 10; ++k) {
    const double rtol = std::pow(10.0, -k);
    char tol[64];
    std::snprintf(tol, sizeof tol, "%.17g", rtol);
    auto integ = make("dopri5", {std::string("rtol=") + tol, std::string("atol=") + tol});
    AdaptiveOptions opt;
    opt.t_end = 5.0;
    const RunResult r = run_adaptive(*sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::ok);
    lx.push_back(std::log10(rtol));
    ly.push_back(std::log10(error_vs_exact(*sys, r)));
  }
  const double n = static_cast<double>(lx.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    sx += lx[i];
    sy += ly[i];
    sxx += lx[i] * lx[i];
    sxy += lx[i] * ly[i];
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  EXPECT_NEAR(slope, 1.0, 0.2);
}

// True evaluation counts of an adaptive run (embedded_rk.hpp): with the starting-step heuristic
// (one evaluation besides f(t0, y0)), an FSAL pair costs 2 + (s-1)(A+R), a non-FSAL one
// 2 + (s-1)(A+R) + (A-1). Several output times do not change this (stage 1 survives a stop).
TEST(AdaptiveEmbedded, EvaluationCountsWithRejections) {
  auto sys = model("kepler", {"e=0.5"});
  for (const auto& t : embedded_tableaux()) {
    auto integ = make(t.name, {"rtol=1e-7", "atol=1e-9"});
    AdaptiveOptions opt;
    opt.t_end = 5.0;
    opt.outputs = 7;
    const RunResult r = run_adaptive(*sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::ok) << t.name;
    const long s = t.stages(), a = r.stats.steps, rej = r.stats.error_test_failures;
    EXPECT_GT(a, 10) << t.name;
    EXPECT_EQ(r.stats.f_evals, t.fsal ? 2 + (s - 1) * (a + rej) : 2 + (s - 1) * (a + rej) + a - 1)
        << t.name;
  }
}

// Van der Pol with μ = 1 (non-stiff) started with h0 = 1: the first trials
// fail the error test, are counted in SolveStats.error_test_failures, and cost s - 1 evaluations
// each (dopri5: 1 + 6(A + R) without the heuristic's extra evaluation).
TEST(AdaptiveEmbedded, RejectedStepsCounted) {
  auto sys = model("van_der_pol", {"mu=1"});
  auto integ = make("dopri5", {"rtol=1e-6", "atol=1e-8", "h0=1"});
  AdaptiveOptions opt;
  opt.t_end = 0.5;
  const RunResult r = run_adaptive(*sys, *integ, opt);
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  EXPECT_GT(r.stats.error_test_failures, 0);
  EXPECT_EQ(r.stats.f_evals, 1 + 6 * (r.stats.steps + r.stats.error_test_failures));
}

// y' = 1 with y(0) = 0 that records the latest time it is evaluated at: every RK method
// reproduces y = t (up to rounding of the step sums), and no stage may lie beyond the
// requested output time.
class RecordingLine final : public OdeSystem {
 public:
  std::string name() const override { return "line"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Zero(1); }
  mutable double t_max = -1.0;

 protected:
  void eval_rhs(double t, CVecRef, VecRef d) const override {
    t_max = std::max(t_max, t);
    d[0] = 1.0;
  }
};

TEST(AdaptiveEmbedded, AdvanceToLandsExactlyOnOutputTimes) {
  RecordingLine sys;
  for (const auto& t : embedded_tableaux()) {
    auto integ = make(t.name, {"h0=0.3"});  // steps of 0.3 (f' = 0: error 0, growth capped)
    Vec y = sys.initial_state();
    SolveStats stats;
    integ->reset(sys, 0.0, y);
    for (const double t_out : {0.1, 0.37, 1.0, 1.2345, 10.0}) {
      sys.t_max = -1.0;
      ASSERT_EQ(integ->advance_to(sys, t_out, y, stats), Status::ok);
      EXPECT_NEAR(y[0], t_out, 1e-14 * t_out) << t.name;
      // Stage times t + c_i h with h = t_out - t on the last step: at most an ulp past t_out.
      EXPECT_LE(sys.t_max, t_out * (1 + 2 * std::numeric_limits<double>::epsilon())) << t.name;
    }
  }
}

// --- radau5 -------------------------------------------------------------------------------

// The transformation built from A⁻¹'s eigenvectors against the closed forms of RADAU5 (Hairer &
// Wanner's code): γ̂ = 30/(6 + 81^⅓ - 9^⅓), a ± ib = (α ± iβ)/(α² + β²) with
// α = (12 - 81^⅓ + 9^⅓)/60, β = (81^⅓ + 9^⅓)√3/60; and the error weights γ̂ e =
// (-(13 + 7√6)/3, (-13 + 7√6)/3, -1/3) (HW IV.8, eq. (8.20)).
TEST(Radau5, TransformationAndErrorWeights) {
  const ButcherTableau& tab = radau5_tableau();
  EXPECT_LE(tab.row_sum_defect(), 1e-15);
  for (int p = 1; p <= 5; ++p) EXPECT_LE(tab.order_defect(p), 1e-14) << p;
  EXPECT_GT(tab.order_defect(6), 1e-6);
  const Radau5Constants& k = radau5_constants();
  const Eigen::Matrix3d lambda = k.t_inv * Eigen::Matrix3d(tab.a).inverse() * k.t;
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  expected(0, 0) = k.gamma_hat;
  expected(1, 1) = expected(2, 2) = k.a;
  expected(1, 2) = k.b;
  expected(2, 1) = -k.b;
  EXPECT_LE((lambda - expected).cwiseAbs().maxCoeff(), 1e-12);
  const double c81 = std::cbrt(81.0), c9 = std::cbrt(9.0), r6 = std::sqrt(6.0);
  EXPECT_NEAR(k.gamma_hat, 30.0 / (6.0 + c81 - c9), 1e-13);
  const double al = (12.0 - c81 + c9) / 60.0, be = (c81 + c9) * std::sqrt(3.0) / 60.0;
  EXPECT_NEAR(k.a, al / (al * al + be * be), 1e-13);
  EXPECT_NEAR(std::abs(k.b), be / (al * al + be * be), 1e-13);
  EXPECT_NEAR(k.gamma_hat * k.e[0], -(13.0 + 7.0 * r6) / 3.0, 1e-12);
  EXPECT_NEAR(k.gamma_hat * k.e[1], (-13.0 + 7.0 * r6) / 3.0, 1e-12);
  EXPECT_NEAR(k.gamma_hat * k.e[2], -1.0 / 3.0, 1e-12);
}

// Fixed steps on the eccentric Kepler orbit (non-stiff, exact solution): order 5. h = 0.04 / 2^k,
// k = 0..3 (errors 7e-7 … 2e-11, measured order 5.00 in the last pair).
TEST(Radau5, FixedStepOrderFiveOnKepler) {
  ConvergenceSpec spec;
  spec.model = "kepler";
  spec.params = Params::from_assignments({"e=0.5"});
  spec.integrators = {"radau5"};
  spec.t_end = 5;
  spec.h = 0.04;
  spec.levels = 4;
  const auto res = run_convergence(spec, nullptr);
  const auto p = last_observed_order(res.rows, "radau5");
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(*p, 5.0, 0.2);
}

// Prothero–Robinson y' = λ(y - sin t) + cos t with λ = -1e6 and h|λ| ≥ 3e4: the order drops to
// the stage order q = 3 (HW II §IV.15; Prothero & Robinson 1974). With z = hλ the error obeys
// e_{n+1} = R(z) e_n + δ, δ = z bᵀ(I - zA)⁻¹ Δ + O(h⁶), where Δ_i = O(h^(q+1)) are the stage
// defects of φ. Stiffly accurate: z bᵀ(I - zA)⁻¹ = -e_sᵀ - e_sᵀ(zA)⁻¹ + O(z⁻²) and Δ_s is the
// quadrature error O(h⁶), so δ = O(h^(q+1)/(h|λ|)) = O(h³/|λ|), and R(∞) = 0 keeps e_n ~ δ:
// order 3, and the error ten times smaller for λ ten times larger. h = 0.5 / 2^k, k = 0..4,
// t_end = 10 (measured 2.97 in the last pair; errors 5e-10 … 2e-13).
TEST(Radau5, ProtheroRobinsonStageOrderThree) {
  ConvergenceSpec spec;
  spec.model = "prothero_robinson";
  spec.integrators = {"radau5"};
  spec.t_end = 10;
  spec.h = 0.5;
  spec.levels = 5;
  const auto res = run_convergence(spec, nullptr);
  const auto p = last_observed_order(res.rows, "radau5");
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(*p, 3.0, 0.2);
  // Error ∝ 1/|λ| at fixed h.
  std::vector<double> err;
  for (const char* lambda : {"lambda=-1e5", "lambda=-1e6"}) {
    auto sys = model("prothero_robinson", {lambda});
    auto integ = make("radau5");
    FixedStepOptions opt;
    opt.t_end = 10.0;
    opt.h = 0.125;
    const RunResult r = run_fixed_step(*sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::ok);
    err.push_back(error_vs_exact(*sys, r));
  }
  EXPECT_NEAR(err[0] / err[1], 10.0, 1.0);
}

// mescd of the IVP test set: -log10 max_i |y_i - ref_i| / (atol/rtol + |ref_i|).
double mescd(CVecRef y, CVecRef ref, double ratio) {
  return -std::log10(((y - ref).array().abs() / (ratio + ref.array().abs())).maxCoeff());
}

// HIRES at t = 321.8122 with rtol = 1e-10, atol = 1e-12 against the IVP test set's reference
// solution (as in tests/models/test_stiff_problems.cpp; docs/reference-values.md): mescd ≥ 6, and
// the counters of the run are filled in (measured: mescd 12.3, 1744 steps).
TEST(Radau5, HiresMatchesPublishedReference) {
  auto sys = model("hires");
  auto integ = make("radau5", {"rtol=1e-10", "atol=1e-12"});
  AdaptiveOptions opt;
  opt.t_end = 321.8122;
  const RunResult r = run_adaptive(*sys, *integ, opt);
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  const Vec ref{{0.7371312573325668e-3, 0.1442485726316185e-3, 0.5888729740967575e-4,
                 0.1175651343283149e-2, 0.2386356198831331e-2, 0.6238968252742796e-2,
                 0.2849998395185769e-2, 0.2850001604814231e-2}};
  EXPECT_GE(mescd(r.y, ref, 1e-12 / 1e-10), 6.0);
  EXPECT_GT(r.stats.steps, 100);
  EXPECT_GT(r.stats.newton_iters, r.stats.steps);
  EXPECT_GE(r.stats.jac_evals, 1);
  EXPECT_GT(r.stats.linear_setups, 0);
  // Two solves (real + complex) per Newton iteration, one or two per error estimate.
  EXPECT_GE(r.stats.lin_solves, 2 * r.stats.newton_iters + r.stats.steps);
}

// VDPOL (ε = 1e-6, scaled form, t = 2; models/problems/van_der_pol.hpp) and Robertson to
// t = 1e11 (models/problems/robertson.hpp) at rtol = 1e-8, atol = 1e-10, against the published
// reference values quoted in those headers: mescd ≥ 6 (measured 11.4 and 13.1).
TEST(Radau5, VanDerPolAndRobertsonMatchPublishedReferences) {
  const std::vector<std::tuple<std::string, double, Vec>> cases = {
      {"van_der_pol", 2.0, Vec{{0.1706167732170483e+01, -0.8928097010247975e+00}}},
      {"robertson", 1e11,
       Vec{{0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050e+00}}}};
  for (const auto& [name, t_end, ref] : cases) {
    auto sys = model(name);
    auto integ = make("radau5", {"rtol=1e-8", "atol=1e-10"});
    AdaptiveOptions opt;
    opt.t_end = t_end;
    const RunResult r = run_adaptive(*sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::ok) << name << ": " << r.stats.message;
    EXPECT_GE(mescd(r.y, ref, 1e-2), 6.0) << name;
    EXPECT_GT(r.stats.newton_iters, r.stats.steps) << name;
  }
}

// A stiff van der Pol (ε = 1e-6) started with h0 = 0.1 over its first fast transient: the
// estimate rejects the too-large steps (and Newton may fail), counted in error_test_failures, and
// the run still ends ok and agrees with a tight run.
TEST(Radau5, RejectionsCountedOnStiffVanDerPol) {
  auto sys = model("van_der_pol");
  auto integ = make("radau5", {"rtol=1e-6", "atol=1e-6", "h0=0.1"});
  AdaptiveOptions opt;
  opt.t_end = 2.0;
  const RunResult r = run_adaptive(*sys, *integ, opt);
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  EXPECT_GT(r.stats.error_test_failures, 0);
  auto tight = make("radau5", {"rtol=1e-10", "atol=1e-10"});
  const RunResult t = run_adaptive(*sys, *tight, opt);
  ASSERT_EQ(t.stats.status, Status::ok) << t.stats.message;
  EXPECT_LT((r.y - t.y).cwiseAbs().maxCoeff() / (1e-6 + t.y.cwiseAbs().maxCoeff()), 1e-3);
}

// The sparse path (SparseLU on the real and the complex matrix) gives the dense path's run.
TEST(Radau5, SparseMatchesDense) {
  auto sys = model("hires");
  AdaptiveOptions opt;
  opt.t_end = 10.0;
  auto d = make("radau5", {"rtol=1e-8", "atol=1e-10", "linear_solver=dense_lu"});
  auto s = make("radau5", {"rtol=1e-8", "atol=1e-10", "linear_solver=sparse_lu"});
  const RunResult rd = run_adaptive(*sys, *d, opt);
  const RunResult rs = run_adaptive(*sys, *s, opt);
  ASSERT_EQ(rs.stats.status, Status::ok);
  EXPECT_EQ(rd.stats.steps, rs.stats.steps);
  EXPECT_LT((rd.y - rs.y).cwiseAbs().maxCoeff(), 1e-12 * rd.y.cwiseAbs().maxCoeff());
}

// --- the step-size floor and the admissible set ------------------------------------------------

// y' = y², y(0) = 1: y = 1/(1 - t) blows up at t = 1. A numerical solution with y_n at t_n blows
// up at t_n + 1/y_n, which the global error moves off 1 by O(rtol). Approaching it, an
// error-controlled step shrinks with the distance to the singularity (h ≈ c·(t* - t), c < 1 set by
// the tolerance), so it reaches the floor 10·u·|t| ≈ 1.1e-15 (u = 2^-53) within 1e-4 of t = 1
// (rtol = 1e-6; measured: 1e-9 to 2e-5 after it), with y ≈ 1/(t* - t) > 1e8, still finite.
// Every method on the shared adaptive loop ends there with step_size_too_small.
class QuadraticBlowUp final : public OdeSystem {
 public:
  std::string name() const override { return "quadratic_blow_up"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool autonomous() const override { return true; }

 protected:
  void eval_rhs(double, CVecRef y, VecRef d) const override { d[0] = y[0] * y[0]; }
};

// The number after `key` in `text` (NaN when absent).
double number_after(const std::string& text, const std::string& key) {
  const auto at = text.find(key);
  if (at == std::string::npos) return std::numeric_limits<double>::quiet_NaN();
  return std::stod(text.substr(at + key.size()));
}

TEST(AdaptiveStepFloor, FiniteTimeSingularityEndsStepSizeTooSmallNearIt) {
  const QuadraticBlowUp sys;
  for (const std::string name : {"dopri5", "bs3", "radau5", "rodas4", "esdirk43"}) {
    auto integ = make(name, {"rtol=1e-6", "atol=1e-6"});
    AdaptiveOptions opt;
    opt.t_end = 2.0;
    const RunResult r = run_adaptive(sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::step_size_too_small) << name << ": " << r.stats.message;
    EXPECT_EQ(to_string(r.stats.status), "step_size_too_small");
    const std::string& m = r.stats.message;
    EXPECT_NE(m.find("step size too small"), std::string::npos) << m;
    const double t = number_after(m, "at t = ");
    EXPECT_NEAR(t, 1.0, 1e-4) << name << ": " << m;
    // The step that failed is at or below 10·u·t; the largest component is y ≈ 1/(1 - t).
    EXPECT_LE(number_after(m, "h = "), 10.0 * 0.5 * std::numeric_limits<double>::epsilon() * t)
        << m;
    EXPECT_GT(number_after(m, "y[0] = "), 1e8) << name << ": " << m;
  }
}

// The floor is 10·u·|t| (u = ε/2) and has none at t = 0.
TEST(AdaptiveStepFloor, LimitIsTenUnitRoundoffsOfT) {
  const double u = 0.5 * std::numeric_limits<double>::epsilon();
  EXPECT_EQ(step_too_small_limit(0.0), 0.0);
  EXPECT_EQ(step_too_small_limit(1.0), 10.0 * u);
  EXPECT_EQ(step_too_small_limit(-4.0), 40.0 * u);
  EXPECT_EQ(step_too_small_limit(1e11), 10.0 * u * 1e11);
}

// Robertson at rtol = atol = 1e-4 with radau5, one output at t = 1e11: Hairer's RADAU5 stops with
// "step size too small" near t = 0.14; a run that goes on reaches concentrations far below zero
// (y1 ≈ -4.7e7), outside the model's admissible set. Either way the run must not end ok.
TEST(AdaptiveStepFloor, RobertsonAtLooseToleranceIsNeverOk) {
  auto sys = model("robertson");
  auto integ = make("radau5", {"rtol=1e-4", "atol=1e-4"});
  AdaptiveOptions opt;
  opt.t_end = 1e11;
  opt.outputs = 1;
  const RunResult r = run_adaptive(*sys, *integ, opt);
  EXPECT_TRUE(r.stats.status == Status::step_size_too_small ||
              r.stats.status == Status::invalid_state)
      << to_string(r.stats.status) << ": " << r.stats.message;
}

}  // namespace
}  // namespace stiffbench

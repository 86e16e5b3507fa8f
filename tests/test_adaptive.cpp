// The shared step-size controller and the methods that use it (integrators/adaptive/): embedded
// explicit pairs and Radau IIA. Expected numbers come from theory (order conditions, the
// evaluation counts each header derives, tolerance proportionality) or from exact solutions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "core/driver.hpp"
#include "experiments/convergence.hpp"
#include "integrators/explicit/tableaux.hpp"
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
// of log(error) against log(rtol), fitted by least squares over rtol = 1e-4 .. 1e-10.
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
    const long s = t.stages(), a = r.stats.steps, rej = r.stats.rejected_steps;
    EXPECT_GT(a, 10) << t.name;
    EXPECT_EQ(r.stats.f_evals, t.fsal ? 2 + (s - 1) * (a + rej) : 2 + (s - 1) * (a + rej) + a - 1)
        << t.name;
  }
}

// Van der Pol with μ = 1 (non-stiff) started with h0 = 1: the first trials
// fail the error test, are counted in SolveStats.rejected_steps, and cost s - 1 evaluations
// each (dopri5: 1 + 6(A + R) without the heuristic's extra evaluation).
TEST(AdaptiveEmbedded, RejectedStepsCounted) {
  auto sys = model("van_der_pol", {"mu=1"});
  auto integ = make("dopri5", {"rtol=1e-6", "atol=1e-8", "h0=1"});
  AdaptiveOptions opt;
  opt.t_end = 0.5;
  const RunResult r = run_adaptive(*sys, *integ, opt);
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  EXPECT_GT(r.stats.rejected_steps, 0);
  EXPECT_EQ(r.stats.f_evals, 1 + 6 * (r.stats.steps + r.stats.rejected_steps));
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

}  // namespace
}  // namespace stiffbench

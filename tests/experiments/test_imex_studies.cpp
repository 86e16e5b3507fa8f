// The studies on split models.
//  - convergence on Kaps' problem (eps = 1e-6, stiff: h/eps >= 3e3 on the whole ladder) with the
//    IMEX methods: each fitted order is within 0.15 of the classical one, or the study names an
//    order reduction to the fitted value. Which applies is derived from the tables: a globally
//    stiffly accurate (GSA) pair — both tables' last rows equal their weights, so y⁺ is the last
//    stage z_s, which solves the stiff equation z = ψ + h a_ss f_I(z) and so lies within O(eps) of
//    the slow manifold y1 = y2² — keeps its classical order in the stiff limit (Boscarino, SIAM J.
//    Numer. Anal. 45, 2007: the IMEX method then acts on the limiting index-1 DAE as its explicit
//    table on the reduced ODE); a pair that is not GSA combines stages and may lose orders there.
//  - lie and strang on Kaps: the splitting error vanishes (the exact solution stays on
//    y1 = y2², where f_I = 0, and f_E's flow keeps that curve invariant: d(y1 - y2²)/dt =
//    -2y1 - 2y2(y1 - y2 - y2²) = 0 on it; f_I's flow, y1' = (y2² - y1)/eps with y2 fixed, keeps
//    it too), so a splitting converges with its sub-integrators' order. With sub-integrators of
//    the splitting's own order (lie: euler + backward_euler, strang: heun + sdirk2) that is 1
//    and 2 within 0.15; with higher-order ones (heun + sdirk2 under lie: 2 against the declared
//    min(1, 2, 2) = 1) the study names the higher order instead of calling it pre-asymptotic.
//    tests/integrators/test_operator_splitting.cpp measures the splitting orders 1 and 2 on a
//    split whose parts do not commute.
//  - stability on advection_diffusion (advection explicit, diffusion implicit) with ark436l2sa:
//    predicted from the explicit table's imaginary-axis limit over the advection operator's
//    largest |eigenvalue| (a/Δx)·max|sin(2πm/N)| = N for a = 1 and N divisible by 4 (N = 256, the
//    default: at nu = 1e-3 the diffusion, 4nu/Δx² = 262, is as fast as the advection); measured
//    within 0.9-1.1 of it, and not lower when the diffusion coefficient is raised tenfold (while
//    rk4's limit, set by the whole spectrum, falls).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/theory/linear_stability.hpp"
#include "experiments/studies/convergence.hpp"
#include "experiments/studies/stability.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;

bool globally_stiffly_accurate(const AdditiveTableau& t) {
  const auto last_row_is_b = [](const ButcherTableau& b) {
    const int s = b.stages();
    return (b.a.row(s - 1).transpose() - b.b).cwiseAbs().maxCoeff() < 1e-14;
  };
  return last_row_is_b(t.explicit_table) && last_row_is_b(t.implicit_table);
}

ConvergenceSpec kaps_convergence(const std::vector<std::string>& integrators) {
  ConvergenceSpec spec;
  spec.model = "kaps";
  spec.params.set("eps", "1e-6");
  spec.integrators = integrators;
  spec.t_end = 1.0;
  spec.h = 0.1;
  spec.levels = 6;
  return spec;
}

TEST(ImexStudies, KapsOrdersClassicalOrReductionNamed) {
  const ConvergenceSpec spec = kaps_convergence({"imex_euler", "ars232", "ars443", "ark324l2sa",
                                                 "ark436l2sa", "imex_ssp2_222", "lie", "strang"});
  const ConvergenceResult r = run_convergence(spec, nullptr);
  ASSERT_EQ(r.fits.size(), spec.integrators.size());
  for (const OrderFit& f : r.fits) {
    SCOPED_TRACE(f.integrator + ": " + f.reason);
    ASSERT_TRUE(f.fitted.has_value());
    const auto integ = make(f.integrator);
    if (const AdditiveTableau* t = integ->additive_tableau()) {
      const bool classical = std::abs(*f.fitted - f.order) <= 0.15;
      if (globally_stiffly_accurate(*t)) {
        EXPECT_TRUE(classical) << *f.fitted;
      } else if (!classical) {
        EXPECT_LT(*f.fitted, f.order);
        EXPECT_EQ(f.reason.rfind("order reduction to " + format_fixed(*f.fitted, 2), 0), 0u);
      }
    } else {
      EXPECT_GE(*f.fitted, f.order - 0.15);  // lie, strang: no splitting error here
    }
  }
}

// Splittings with sub-integrators of their own order show 1 (lie) and 2 (strang); heun + sdirk2
// under lie shows 2, named as higher than the declared order 1 (see the comment at the top).
TEST(ImexStudies, KapsSplittingOrdersWithMatchedSubIntegrators) {
  const auto fits = [](const std::string& ex, const std::string& im) {
    ConvergenceSpec spec = kaps_convergence({"lie", "strang"});
    spec.params.set("explicit", ex);
    spec.params.set("implicit", im);
    return run_convergence(spec, nullptr).fits;
  };
  const std::vector<OrderFit> first = fits("euler", "backward_euler");
  const std::vector<OrderFit> second = fits("heun", "sdirk2");
  ASSERT_EQ(first.size(), 2u);
  ASSERT_EQ(second.size(), 2u);
  // lie: order 1; strang with first-order parts: min(2, 1, 1) = 1.
  EXPECT_EQ(first[0].order, 1);
  EXPECT_EQ(first[1].order, 1);
  ASSERT_TRUE(first[0].fitted.has_value());
  EXPECT_NEAR(*first[0].fitted, 1.0, 0.15) << first[0].reason;
  ASSERT_TRUE(second[1].fitted.has_value());
  EXPECT_EQ(second[1].order, 2);
  EXPECT_NEAR(*second[1].fitted, 2.0, 0.15) << second[1].reason;
  ASSERT_TRUE(second[0].fitted.has_value());
  EXPECT_EQ(second[0].order, 1);
  EXPECT_NEAR(*second[0].fitted, 2.0, 0.15);
  EXPECT_EQ(second[0].reason.rfind("a higher order than the classical 1", 0), 0u)
      << second[0].reason;
}

StabilityResult advection_diffusion_stability(const std::string& nu) {
  StabilitySpec spec;
  spec.model = "advection_diffusion";
  spec.params.set("n", "256");
  spec.params.set("nu", nu);
  spec.integrators = {"ark436l2sa", "rk4"};
  return run_stability(spec, nullptr);
}

const StabilityRow& row_of(const StabilityResult& r, const std::string& name) {
  for (const auto& row : r.rows)
    if (row.integrator == name) return row;
  throw std::runtime_error("no row " + name);
}

TEST(ImexStudies, AdvectionDiffusionLimitFromTheExplicitPart) {
  const StabilityResult base = advection_diffusion_stability("1e-4");
  const StabilityResult stiff = advection_diffusion_stability("1e-3");
  const auto ark = make("ark436l2sa");
  const LinearStability le = tableau_stability(ark->additive_tableau()->explicit_table);
  const double predicted = imaginary_axis_limit(le).limit / 256.0;
  ASSERT_GT(predicted, 0.0);
  const StabilityRow& a = row_of(base, "ark436l2sa");
  EXPECT_EQ(a.predicted_on, "f_E");
  EXPECT_EQ(a.status, "ok");
  ASSERT_TRUE(a.h_predicted && a.h_measured);
  EXPECT_NEAR(*a.h_predicted, predicted, 1e-9 * predicted);
  EXPECT_GE(*a.h_measured / *a.h_predicted, 0.9);
  EXPECT_LE(*a.h_measured / *a.h_predicted, 1.1);
  const StabilityRow& b = row_of(stiff, "ark436l2sa");
  ASSERT_TRUE(b.h_measured);
  EXPECT_GE(*b.h_measured, *a.h_measured * (1 - 2e-3));  // within the bisection's tolerance
  // rk4 sees the whole spectrum: ten times the diffusion lowers its limit.
  const StabilityRow& r0 = row_of(base, "rk4");
  const StabilityRow& r1 = row_of(stiff, "rk4");
  ASSERT_TRUE(r0.h_measured && r1.h_measured);
  EXPECT_LT(*r1.h_measured, *r0.h_measured);
  EXPECT_EQ(r0.predicted_on, "f");
}

}  // namespace
}  // namespace stiffbench

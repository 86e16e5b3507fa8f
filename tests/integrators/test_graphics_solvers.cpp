// The graphics solvers for stiff springs (integrators/graphics/): projective dynamics against the
// project's backward Euler (Newton to a tight tolerance, an independent computation of the same
// implicit step), XPBD against tight reference solutions of the spring ODE, both orders on the
// spring chain's exact normal-mode solution, and refusal of systems without springs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "core/springs.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/studies/convergence.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

// y after `steps` steps of size h of `method` from y0 at t = 0.
Vec advance(const OdeSystem& sys, const std::string& method, const std::vector<std::string>& params,
            double h, int steps, const Vec& y0) {
  auto integ = make(method, params);
  FixedStepOptions opt;
  opt.h = h;
  opt.t_end = h * steps;
  const RunResult r = run_fixed_step_from(sys, *integ, 0.0, y0, opt);
  EXPECT_EQ(r.stats.status, Status::ok) << method;
  EXPECT_EQ(r.n_steps, steps);
  return r.y;
}

TEST(GraphicsSolvers, RefuseSystemsWithoutSpringsNamingTheModel) {
  auto kepler = model("kepler");
  for (const std::string name : {"xpbd", "projective_dynamics"}) {
    auto integ = make(name);
    EXPECT_TRUE(integ->info().requires_.spring_network);
    EXPECT_NE(describe_requirements(integ->info().requires_).find("spring network"),
              std::string::npos);
    try {
      integ->reset(*kepler, 0.0, kepler->initial_state());
      ADD_FAILURE() << name << " accepted kepler";
    } catch (const BadInput& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("'kepler'"), std::string::npos) << what;
      EXPECT_NE(what.find("spring network"), std::string::npos) << what;
    }
  }
  // Every mass-spring model offers the view, with its points and springs.
  auto cloth = model("cloth", {"n=4"});
  const SpringNetworkView* v = cloth->spring_network();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->dim, 3);
  EXPECT_EQ(v->points(), 16);
  // 4 × 4 grid: 24 structural, 18 shear, 16 bend springs.
  EXPECT_EQ(v->springs.size(), 58u);
  EXPECT_EQ(kepler->spring_network(), nullptr);
}

TEST(GraphicsSolvers, ProjectiveDynamicsRefusesDashpots) {
  auto cloth = model("cloth", {"n=4", "dashpot=0.01"});
  auto integ = make("projective_dynamics");
  try {
    integ->reset(*cloth, 0.0, cloth->initial_state());
    ADD_FAILURE() << "dashpots accepted";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("dashpot"), std::string::npos) << e.what();
  }
  auto damped = model("cloth", {"n=4", "damping=0.1"});  // point damping: handled exactly
  EXPECT_NO_THROW(integ->reset(*damped, 0.0, damped->initial_state()));
}

// Projective dynamics is a fixed-point iteration for the backward-Euler step (Liu et al. 2013):
// its difference to the project's backward_euler (full Newton to 1e-14, an independent solve of
// the same implicit equations through f and its Jacobian) must fall with the iteration count.
// 16 × 16 cloth (defaults), from the state after 20 backward-Euler steps (moving, stretched),
// one step of h = 0.01; full-state max-norm (the velocities, (x⁺ - x)/h, carry the largest
// difference). Measured: 1.73e-3, 4.82e-4, 1.39e-4, 4.09e-5, ... 7.2e-7 (8 iterations), 1.39e-7
// (10), 6.3e-11 (20): linear convergence, asymptotic ratio 0.47 per iteration. With point damping
// 0.5 (in M + hγI): 4.7e-9 at 10 iterations, ratio 0.37. At h = 0.02 the ratio is 0.75 (about 27
// iterations for 1e-6): the iteration slows as h²k/m grows.
TEST(GraphicsSolvers, ProjectiveDynamicsConvergesToTheBackwardEulerStepOnCloth) {
  for (const std::vector<std::string>& params :
       {std::vector<std::string>{}, std::vector<std::string>{"damping=0.5"}}) {
    SCOPED_TRACE(params.empty() ? "undamped" : params[0]);
    auto sys = model("cloth", params);
    ASSERT_EQ(sys->dimension(), 2 * 3 * 256);
    const Vec y0 = advance(*sys, "backward_euler", {}, 0.01, 20, sys->initial_state());
    const double h = 0.01;
    const Vec be = advance(*sys, "backward_euler", {"newton=full", "newton_tol=1e-14"}, h, 1, y0);
    double previous = 1e300;
    for (int it = 1; it <= 20; ++it) {
      const Vec pd =
          advance(*sys, "projective_dynamics", {"iterations=" + std::to_string(it)}, h, 1, y0);
      const double diff = max_abs_diff(pd, be);
      EXPECT_LT(diff, previous) << it << " iterations";
      if (it == 10) {
        EXPECT_LT(diff, 1e-6);
      }
      if (it == 20) {
        EXPECT_LT(diff, 1e-9);
      }
      previous = diff;
    }
  }
}

// Orders on the spring chain's exact normal-mode solution (fixed-fixed, N = 10, k = m = 1, mode
// 1; docs/reference-values.md), global error at t = 10, h = 0.1 / 2^k: both methods are first order
// (projective dynamics converges to backward Euler; XPBD's substep is an implicit position
// update). In 1D the projection d = L sign(x_j - x_i) does not change while springs keep their
// orientation, so projective dynamics is backward Euler after one iteration here.
TEST(GraphicsSolvers, FirstOrderOnTheSpringChainsExactSolution) {
  for (const std::string name : {"xpbd", "projective_dynamics"}) {
    ConvergenceSpec spec;
    spec.model = "spring_chain";
    spec.integrators = {name};
    spec.t_end = 10;
    spec.h = 0.1;
    spec.levels = 5;
    const auto res = run_convergence(spec, nullptr);
    const auto p = last_observed_order(res.rows, name);
    ASSERT_TRUE(p.has_value()) << name;
    EXPECT_NEAR(*p, 1.0, 0.2) << name;
  }
}

// XPBD approaches the solution of the spring ODE as the substeps grow (h_s = h/substeps → 0,
// first order in h_s). Reference: rk4 at h/1000 (it agrees with rk4 at h/2000 to ~4e-12 on the
// pendulum chain, 6e-13 on the cloth; checked below). Both variants, with one sweep per substep
// (Macklin et al. 2019) and with ten. Rate = log2(e(S/2)/e(S)) over S = 16, 32, 64, which must
// be 1 ± 0.2.
//  - pendulum_chain (5 links, k = 1e4: ω ≈ 450, stiff springs), h = 0.01, t = 0.1, position
//    error: the velocity error is dominated by the fast spring oscillation (v ~ ω m g/k), which
//    XPBD damps until h_s ω ≪ 1, so it converges more slowly in this range. Measured position
//    errors at S = 8..64 (Gauss-Seidel, 1 iteration): 6.1e-4, 3.1e-4, 1.6e-4, 8.5e-5 (rates
//    0.98, 0.92, 0.94); Jacobi, 1 iteration: 1.0e-3, 3.3e-4, 1.6e-4, 8.4e-5.
//  - cloth 8 × 8 (defaults), h = 0.01, t = 0.1, full state: Gauss-Seidel 1 iteration 5.5e-4,
//    2.9e-4, 1.5e-4, 7.6e-5 in x and 2.6e-2, 1.4e-2, 6.9e-3, 3.5e-3 in v (rates ≈ 0.95); Jacobi
//    alike.
TEST(GraphicsSolvers, XpbdApproachesTheSpringSolutionAsSubstepsGrow) {
  struct Case {
    std::string model;
    std::vector<std::string> params;
    bool positions_only;
    double ref_agreement;
  };
  for (const Case& c :
       {Case{"pendulum_chain", {}, true, 1e-10}, Case{"cloth", {"n=8"}, false, 1e-11}}) {
    auto sys = model(c.model, c.params);
    const Vec y0 = sys->initial_state();
    const double h = 0.01;
    const int frames = 10;
    const Vec ref = advance(*sys, "rk4", {}, h / 1000, frames * 1000, y0);
    const Vec ref2 = advance(*sys, "rk4", {}, h / 2000, frames * 2000, y0);
    ASSERT_LT(max_abs_diff(ref, ref2), c.ref_agreement) << c.model;
    const Index n = c.positions_only ? y0.size() / 2 : y0.size();
    for (const std::string variant : {"gauss_seidel", "jacobi"})
      for (const int iterations : {1, 10}) {
        SCOPED_TRACE(c.model + " " + variant + " iterations=" + std::to_string(iterations));
        std::vector<double> err;
        for (const int s : {8, 16, 32, 64}) {
          const Vec x = advance(*sys, "xpbd",
                                {"substeps=" + std::to_string(s),
                                 "iterations=" + std::to_string(iterations), "variant=" + variant},
                                h, frames, y0);
          err.push_back(max_abs_diff(x.head(n), ref.head(n)));
        }
        for (std::size_t k = 1; k < err.size(); ++k) {
          EXPECT_LT(err[k], err[k - 1]);
          if (k >= 2) {
            EXPECT_NEAR(std::log2(err[k - 1] / err[k]), 1.0, 0.2) << k;
          }
        }
      }
  }
}

// Damping in XPBD: dashpots as the paper's constraint damping (γ_c = c/(k h_s)) and point damping
// in the prediction. On the 8 × 8 cloth with dashpot = 0.1 and point damping 0.05 the damped
// solution differs from the undamped one by 0.12 at t = 0.1 (rk4 references at h/1000, which
// agree with h/2000 to 3e-13), and XPBD (one iteration per substep) converges to the damped one at
// rate 1 in the substeps. Measured full-state errors at S = 16, 32, 64: Gauss-Seidel 1.0e-3,
// 5.2e-4, 2.6e-4; Jacobi 4.4e-3, 2.2e-3, 1.1e-3. A missing or wrongly signed damping term would
// leave an error of the order of the damping's effect.
TEST(GraphicsSolvers, XpbdDampingConvergesToTheDampedSolution) {
  auto sys = model("cloth", {"n=8", "dashpot=0.1", "damping=0.05"});
  auto undamped = model("cloth", {"n=8"});
  const Vec y0 = sys->initial_state();
  const double h = 0.01;
  const int frames = 10;
  const Vec ref = advance(*sys, "rk4", {}, h / 1000, frames * 1000, y0);
  const double effect =
      max_abs_diff(ref, advance(*undamped, "rk4", {}, h / 1000, frames * 1000, y0));
  EXPECT_GT(effect, 0.05);
  for (const std::string variant : {"gauss_seidel", "jacobi"}) {
    SCOPED_TRACE(variant);
    std::vector<double> err;
    for (const int s : {16, 32, 64})
      err.push_back(max_abs_diff(
          advance(*sys, "xpbd",
                  {"substeps=" + std::to_string(s), "iterations=1", "variant=" + variant}, h,
                  frames, y0),
          ref));
    for (std::size_t k = 1; k < err.size(); ++k)
      EXPECT_NEAR(std::log2(err[k - 1] / err[k]), 1.0, 0.2) << k;
    EXPECT_LT(err.back(), effect / 50);
  }
}

}  // namespace
}  // namespace stiffbench

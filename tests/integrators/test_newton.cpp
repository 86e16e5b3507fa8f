// Newton's stopping test and its failures (integrators/solvers/newton.hpp): the
// contraction-aware rule keeps the Newton error below the truncation error down to round-off,
// accepts after one update only at round-off, and names the reason of a failure.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/driver.hpp"
#include "core/ode_system.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/solvers/newton.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

double final_error(const OdeSystem& sys, Integrator& integ, double t_end, double h) {
  FixedStepOptions opt;
  opt.t_end = t_end;
  opt.h = h;
  const RunResult r = run_fixed_step(sys, integ, opt);
  EXPECT_EQ(r.stats.status, Status::ok) << r.stats.message;
  Vec exact(sys.dimension());
  sys.exact(r.t, exact);
  return (r.y - exact).cwiseAbs().maxCoeff();
}

// (a) On Kepler e = 0.5 the stage Newton used to stop after one update (residual below
// 1e-12), and those errors added up over thousands of steps: esdirk43 went 3.65e-12 -> 7.52e-10
// when h halved from 1.25e-3 to 6.25e-4 (t_end = 2.5), sdirk3 1.24e-8 -> 5.76e-8 from 6.25e-4 to
// 3.125e-4 (t_end = 5). Now each halving divides the error by about 2^p (theory: global order
// p = 4 and 3), or leaves it at the round-off floor N·ε·max|y| (N steps, |y| <= 3 on this orbit).
// The bound allows a factor 2 over 2^-p.
TEST(NewtonStopping, KeplerErrorFallsAtTheMethodsOrderAtFineSteps) {
  auto sys = model("kepler", {"e=0.5"});
  struct Case {
    const char* name;
    int order;
    double t_end, h;
  };
  for (const Case& c : {Case{"esdirk43", 4, 2.5, 1.25e-3}, Case{"sdirk3", 3, 5.0, 6.25e-4}}) {
    auto integ = make(c.name);
    const double e1 = final_error(*sys, *integ, c.t_end, c.h);
    const double e2 = final_error(*sys, *integ, c.t_end, c.h / 2);
    const double floor = std::round(2 * c.t_end / c.h) * std::numeric_limits<double>::epsilon() * 3;
    EXPECT_LE(e2, std::max(2.0 * std::pow(2.0, -c.order) * e1, floor))
        << c.name << ": " << e1 << " -> " << e2;
  }
}

// (b) A linear problem with the exact Jacobian: the first update solves the stage equation up to
// rounding, but without a contraction rate it is not accepted unless at round-off; the second
// update is at round-off (measured rate ~1e-16) and ends the solve. So every implicit stage takes
// exactly two updates (two linear solves) and two f evaluations (at the two iterates; the accepted
// one is not evaluated), with every Newton mode.
TEST(NewtonStopping, LinearProblemTakesTwoUpdatesPerStage) {
  auto sys = model("dahlquist", {"lambda_re=-3", "lambda_im=5"});
  const std::map<std::string, int> implicit_stages = {
      {"backward_euler", 1}, {"implicit_midpoint", 1},
      {"trapezoidal", 1},    {"sdirk2", 2},
      {"sdirk3", 3},         {"bdf2", 1}};
  for (const auto& [name, stages] : implicit_stages) {
    for (const auto& mode : {"full", "modified", "frozen"}) {
      auto integ = make(name, {std::string("newton=") + mode});
      FixedStepOptions opt;
      opt.t_end = 1.0;
      opt.h = 0.01;
      const RunResult r = run_fixed_step(*sys, *integ, opt);
      ASSERT_EQ(r.stats.status, Status::ok);
      // bdf2's first step is an sdirk2 start-up (2 stages); trapezoidal has an explicit stage.
      const long stage_solves = name == "bdf2" ? 99 + 2 : 100L * stages;
      EXPECT_EQ(r.stats.newton_iters, 2 * stage_solves) << name << " " << mode;
      EXPECT_EQ(r.stats.lin_solves, 2 * stage_solves) << name << " " << mode;
      EXPECT_EQ(r.stats.newton_conv_failures, 0);
      const long explicit_evals = name == std::string("trapezoidal") ? 100 : 0;
      EXPECT_EQ(r.stats.f_evals, 2 * stage_solves + explicit_evals) << name << " " << mode;
    }
  }
  // With one update allowed, the first update is never accepted: it is far above round-off and
  // has no rate, so each solve's first attempt fails (iteration limit, counted) and the retry
  // continues from that iterate, whose next update is at round-off and accepted: 10 steps, 10
  // counted failures, 20 updates.
  auto one = make("backward_euler", {"newton_max_iter=1"});
  FixedStepOptions opt;
  opt.t_end = 0.1;
  opt.h = 0.01;
  const RunResult r = run_fixed_step(*sys, *one, opt);
  EXPECT_EQ(r.stats.status, Status::ok);
  EXPECT_EQ(r.stats.newton_conv_failures, 10);
  EXPECT_EQ(r.stats.newton_iters, 20);
}

// y' = λy (scalar) whose Jacobian has the wrong sign, -λ. Newton with W = 1 + hγλ on
// G(z) = (1 - hγλ) z - ψ multiplies the error by 1 - (1 - hγλ)/(1 + hγλ) = 2hγλ/(1 + hγλ) per
// update: for hγλ = -10 the rate is θ = 20/9 ≈ 2.22 (theory), whatever J is re-evaluated. The
// start y0 = 1e-8 keeps the norm's weights 1 + |z| at 1, so the measured θ is that factor.
class WrongJacobian final : public OdeSystem {
 public:
  explicit WrongJacobian(double lambda) : lambda_(lambda) {}
  std::string name() const override { return "wrong_jacobian"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Constant(1, 1e-8); }
  bool has_jacobian() const override { return true; }

 protected:
  void eval_rhs(double, CVecRef y, VecRef dydt) const override { dydt = lambda_ * y; }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override {
    jac.resize(1, 1);
    jac.insert(0, 0) = -lambda_;
  }

 private:
  double lambda_;
};

// (c) A diverging Newton fails with the reason "diverging" and its rate in the message, after
// each attempt (configured J, then full Newton) failed: both count as convergence failures.
TEST(NewtonStopping, DivergingNewtonSaysSo) {
  WrongJacobian sys(-10.0);
  DirkIntegrator integ(implicit_tableau("backward_euler"), "", {});
  Vec y = sys.initial_state();
  SolveStats stats;
  integ.reset(sys, 0.0, y);
  EXPECT_EQ(integ.step(sys, 0.0, y, 1.0, stats), Status::newton_failed);
  EXPECT_EQ(stats.newton_conv_failures, 2);
  EXPECT_NE(stats.message.find("diverging (theta = 2.2222"), std::string::npos) << stats.message;
  EXPECT_NE(stats.message.find("with full Newton"), std::string::npos) << stats.message;
}

// The shared test itself, on made-up update norms.
TEST(NewtonStopping, SharedRuleOutcomes) {
  NewtonOutcome o;
  double theta = 0;
  const double eps = std::numeric_limits<double>::epsilon();
  // One update: accepted only at round-off.
  EXPECT_FALSE(newton_update_converged(1e-14, 0, false, 1e-12, 1, 10, true, &o, &theta));
  EXPECT_TRUE(newton_update_converged(2 * eps, 0, false, 1e-12, 1, 10, true, &o, &theta));
  EXPECT_EQ(o, NewtonOutcome::converged);
  // θ = 0.1: predicted error 0.1/0.9 · 1e-13 ≈ 1.1e-14 <= 1e-13.
  EXPECT_TRUE(newton_update_converged(1e-13, 1e-12, true, 1e-13, 2, 10, true, &o, &theta));
  EXPECT_EQ(o, NewtonOutcome::converged);
  EXPECT_DOUBLE_EQ(theta, 0.1);
  // θ = 0.5 from 1e-3 with 8 iterations left: 0.5^8/0.5 · 1e-3 = 7.8e-6 > 1e-12: too slow.
  EXPECT_TRUE(newton_update_converged(1e-3, 2e-3, true, 1e-12, 2, 10, true, &o, &theta));
  EXPECT_EQ(o, NewtonOutcome::too_slow);
  // ... which full Newton (slow_test off) keeps iterating.
  EXPECT_FALSE(newton_update_converged(1e-3, 2e-3, true, 1e-12, 2, 10, false, &o, &theta));
  // θ >= 1: diverging above the noise level, converged (rounding noise) below it.
  EXPECT_TRUE(newton_update_converged(1e-3, 5e-4, true, 1e-12, 2, 10, true, &o, &theta));
  EXPECT_EQ(o, NewtonOutcome::diverging);
  EXPECT_TRUE(newton_update_converged(50 * eps, 20 * eps, true, 1e-16, 2, 10, true, &o, &theta));
  EXPECT_EQ(o, NewtonOutcome::converged);
}

// (d) radau5 with newton=frozen keeps J across steps; on HIRES at h = 0.1 (stiff, nonlinear) the
// frozen J goes stale, Newton fails, and the step is retried with a fresh J and refactorised
// matrices instead of ending the run. Each retry follows a counted failure, so there are more
// Jacobians than the first one only through failures (jac_evals <= 1 + 2 · failures: a retry may
// also take J at the step's end). Both modes solve the same stage equations to round-off, so
// their results agree far below the method's error at this step.
TEST(Radau5Newton, FrozenJacobianIsRefreshedAfterAFailure) {
  auto sys = model("hires");
  FixedStepOptions opt;
  opt.t_end = 10.0;
  opt.h = 0.1;
  auto frozen = make("radau5", {"newton=frozen"});
  auto modified = make("radau5", {"newton=modified"});
  const RunResult rf = run_fixed_step(*sys, *frozen, opt);
  const RunResult rm = run_fixed_step(*sys, *modified, opt);
  ASSERT_EQ(rf.stats.status, Status::ok) << rf.stats.message;
  ASSERT_EQ(rm.stats.status, Status::ok) << rm.stats.message;
  EXPECT_GE(rf.stats.newton_conv_failures, 1);
  EXPECT_GT(rf.stats.jac_evals, 1);
  EXPECT_LE(rf.stats.jac_evals, 1 + 2 * rf.stats.newton_conv_failures);
  EXPECT_EQ(rm.stats.jac_evals, 100);  // one per step
  EXPECT_LT(max_abs_diff(rf.y, rm.y), 1e-12);
}

// A radau5 fixed-step failure says why: van der Pol (ε = 1e-6) at h = 0.2 cannot be solved
// near t = 0.2 (the slow manifold bends sharply), and the message names each attempt's reason,
// including the retry with J at the step's end.
TEST(Radau5Newton, FixedStepFailureNamesTheReason) {
  auto sys = model("van_der_pol");
  FixedStepOptions opt;
  opt.t_end = 2.0;
  opt.h = 0.2;
  auto integ = make("radau5");
  const RunResult r = run_fixed_step(*sys, *integ, opt);
  ASSERT_EQ(r.stats.status, Status::newton_failed);
  EXPECT_GE(r.stats.newton_conv_failures, 2);
  EXPECT_NE(r.stats.message.find("with J at the step's start"), std::string::npos)
      << r.stats.message;
  EXPECT_NE(r.stats.message.find("with J at the step's end"), std::string::npos) << r.stats.message;
  EXPECT_TRUE(r.stats.message.find("too slow") != std::string::npos ||
              r.stats.message.find("diverging") != std::string::npos ||
              r.stats.message.find("iteration limit") != std::string::npos)
      << r.stats.message;
}

// Gauss collocation shares the stopping test: on van der Pol (ε = 1e-6) at h = 0.1 the simplified
// Newton with J at the step's start contracts (θ < 1) but too slowly to reach round-off within
// newton_max_iter = 20, and the message says so with the rate.
TEST(GaussNewton, FailureNamesTheReason) {
  auto sys = model("van_der_pol");
  FixedStepOptions opt;
  opt.t_end = 2.0;
  opt.h = 0.1;
  auto integ = make("gauss4");
  const RunResult r = run_fixed_step(*sys, *integ, opt);
  ASSERT_EQ(r.stats.status, Status::newton_failed);
  EXPECT_EQ(r.stats.newton_conv_failures, 1);
  EXPECT_NE(r.stats.message.find("gauss4: simplified Newton failed"), std::string::npos);
  EXPECT_NE(r.stats.message.find("too slow (theta = "), std::string::npos) << r.stats.message;
}

}  // namespace
}  // namespace stiffbench

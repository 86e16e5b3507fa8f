// lie and strang (integrators/splitting/operator_splitting.hpp) on splits with an exact solution
// (tests/integrators/split_test_system.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "core/driver.hpp"
#include "core/theory/linear_stability.hpp"
#include "core/types.hpp"
#include "tests/integrators/split_test_system.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::KapsSplit;
using testing_support::LinearSplit;
using testing_support::make;
using testing_support::model;

// Max-norm error at t = 1 against the exact solution e^(-2t), e^(-t).
double error_at_one(const std::string& integ, const std::vector<std::string>& params, double h,
                    double lambda) {
  LinearSplit sys(lambda);
  auto m = make(integ, params);
  const RunResult r = run_fixed_step(sys, *m, {1.0, h});
  EXPECT_EQ(r.stats.status, Status::ok) << r.stats.message;
  Vec ye(2);
  sys.exact(1.0, ye);
  return max_abs_diff(r.y, ye);
}

// Observed orders log2(e(h)/e(h/2)) over four halvings from h = 0.0125. Theory: the splitting
// error of Lie is O(h), of Strang O(h^2) (Hairer, Lubich & Wanner, Geometric Numerical
// Integration, Sect. II.5), and dominates for small h: the sub-integrators (rk4, sdirk3) have
// orders 4 and 3 (from h = 0.1 strang's ratios climb 1.40, 1.75, 1.88: sdirk3's h^3 error still
// shows at larger steps, measured). lambda = 3: the parts do not commute, and the problem is smooth
// (no order reduction).
TEST(OperatorSplitting, ObservedOrdersOneAndTwo) {
  for (const auto& [name, order] : {std::pair<std::string, double>{"lie", 1.0}, {"strang", 2.0}}) {
    std::vector<double> err;
    for (double h = 0.0125; h > 7e-4; h /= 2) err.push_back(error_at_one(name, {}, h, 3.0));
    for (std::size_t k = 0; k + 1 < err.size(); ++k) {
      const double p = std::log2(err[k] / err[k + 1]);
      EXPECT_NEAR(p, order, 0.1) << name << " halving " << k << ": " << err[k] << " -> "
                                 << err[k + 1];
    }
  }
}

// With f_E = 0 the explicit substeps are the identity (rk4 on y' = 0), so strang is its
// implicit sub-integrator on f_I = f: the same trajectory as sdirk3 run on the whole system (the
// same Newton on the same Jacobian values), up to rounding.
TEST(OperatorSplitting, StrangWithZeroExplicitPartIsItsImplicitSubIntegrator) {
  KapsSplit split(0.01, true);
  auto strang = make("strang", {"implicit=sdirk3"});
  const RunResult a = run_fixed_step(split, *strang, {1.0, 0.05});
  ASSERT_EQ(a.stats.status, Status::ok) << a.stats.message;
  KapsSplit whole(0.01, true);
  auto sdirk3 = make("sdirk3");
  const RunResult b = run_fixed_step(whole, *sdirk3, {1.0, 0.05});
  ASSERT_EQ(b.stats.status, Status::ok);
  EXPECT_LT(max_abs_diff(a.y, b.y), 1e-14 * b.y.cwiseAbs().maxCoeff());
  // Counters: strang evaluated f_E (rk4: 4 per substep, 2 substeps per step) and f_I apart.
  EXPECT_EQ(split.counters().fe_evals, 20 * 2 * 4);
  EXPECT_GT(split.counters().fi_evals, 0);
}

// The sub-integrators' own caches do not leak across the other part's substep: esdirk43 is FSAL
// (its fixed-step runs reuse the last stage's f as the next k_1 when called again at t + h on the
// same storage) and dopri5 too; here the other part changed y in between, so a reused stage would
// be f at a stale state, an O(1) error per step. With the restart before every substep strang
// keeps its order 2.
TEST(OperatorSplitting, SubIntegratorCachesAreRestartedEachSubstep) {
  std::vector<double> err;
  for (double h = 0.1; h > 0.02; h /= 2)
    err.push_back(error_at_one("strang", {"explicit=dopri5", "implicit=esdirk43"}, h, 3.0));
  for (std::size_t k = 0; k + 1 < err.size(); ++k)
    EXPECT_NEAR(std::log2(err[k] / err[k + 1]), 2.0, 0.1) << k;
}

// Integrator::restart() keeps what reset() analysed of the system's structure and clears the
// rest: for every implicit family a restart at a new (t, y) is followed by the same steps, to the
// bit, as a reset there (the same Jacobian values, the same factorisation of the same pattern),
// on a mechanical system (the 8x8 cloth: velocity-form or first-order with K and D mapped into
// J) and a first-order one (Kaps' problem, ε = 1e-3). Operator splitting restarts its
// sub-integrators at every substep.
TEST(OperatorSplitting, RestartStepsAsResetDoes) {
  const std::vector<std::tuple<std::string, std::vector<std::string>, double>> systems = {
      {"cloth", {"n=8"}, 1e-3}, {"kaps", {"eps=1e-3"}, 0.01}};
  for (const auto& [model_name, params, h] : systems)
    for (const std::string name : {"backward_euler", "sdirk3", "esdirk43", "trbdf2", "radau5",
                                   "gauss6", "rodas4", "semi_implicit_euler", "bdf2"}) {
      const auto sys = model(model_name, params);
      const Vec y0 = sys->initial_state();
      Vec y1 = y0;
      for (Index i = 0; i < y1.size(); ++i) y1[i] += 1e-3 * std::sin(1.0 + static_cast<double>(i));
      Vec result[2];
      for (const bool restart : {false, true}) {
        auto integ = make(name);
        SolveStats stats;
        Vec y = y0;
        integ->reset(*sys, 0.0, y);
        for (int k = 0; k < 2; ++k)
          ASSERT_EQ(integ->step(*sys, k * h, y, h, stats), Status::ok) << name;
        y = y1;
        if (restart)
          integ->restart(*sys, 0.5, y);
        else
          integ->reset(*sys, 0.5, y);
        for (int k = 0; k < 3; ++k)
          ASSERT_EQ(integ->step(*sys, 0.5 + k * h, y, h, stats), Status::ok) << name;
        result[restart ? 1 : 0] = y;
      }
      EXPECT_EQ(max_abs_diff(result[0], result[1]), 0.0) << name << " on " << model_name;
    }
}

TEST(OperatorSplitting, BadSubIntegratorsNameTheParameter) {
  auto expect_bad = [](const std::vector<std::string>& params, const std::string& text) {
    try {
      auto m = make("strang", params);
      KapsSplit sys(0.5);
      run_fixed_step(sys, *m, {0.1, 0.05});
      ADD_FAILURE() << "no BadInput for " << params[0];
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  expect_bad({"explicit=no_such_method"}, "parameter 'explicit' = 'no_such_method'");
  expect_bad({"implicit=cvode_bdf"}, "parameter 'implicit' = 'cvode_bdf': an adaptive-only");
  expect_bad({"explicit=velocity_verlet"}, "parameter 'explicit' = 'velocity_verlet'");
  // The implicit view of a non-mechanical model is not mechanical: refused at reset.
  expect_bad({"implicit=velocity_verlet"}, "parameter 'implicit' = 'velocity_verlet'");
  // A model without a split is refused by the splitting itself.
  auto lie = make("lie");
  auto no_split = model("dahlquist");
  EXPECT_THROW(run_fixed_step(*no_split, *lie, {0.1, 0.05}), BadInput);
}

// explicit_part_stability() is the explicit sub-integrator's over one step: for rk4 R(z) = 1 + z +
// z^2/2 + z^3/6 + z^4/24, lie |R(-2.5)| = 0.6484375 and strang (two half steps) R(-1.25)^2 =
// (1889/6144)^2 = 3568321/37748736 (exact fractions by hand); strang's real-axis limit is twice
// rk4's (2.785293563405282, the root of |R| = 1 on the negative axis).
TEST(OperatorSplitting, ExplicitPartStabilityIsTheExplicitSubIntegrators) {
  auto s = make("strang", {"explicit=rk4"});
  const auto ls = s->explicit_part_stability();
  ASSERT_TRUE(ls.has_value());
  EXPECT_NEAR(ls->amplification({-2.5, 0.0}), 3568321.0 / 37748736.0, 1e-12);
  const auto ll = make("lie", {"explicit=rk4"})->explicit_part_stability();
  ASSERT_TRUE(ll.has_value());
  EXPECT_NEAR(ll->amplification({-2.5, 0.0}), 0.6484375, 1e-12);
  const AxisLimit lim = real_axis_limit(*ls);
  EXPECT_TRUE(lim.exact);
  EXPECT_NEAR(lim.limit, 2 * 2.785293563405282, 1e-8);
  EXPECT_FALSE(s->linear_stability().has_value());
  EXPECT_EQ(s->info().order, 2);
  EXPECT_EQ(make("lie")->info().order, 1);
  EXPECT_EQ(s->info().family, Family::operator_splitting);
}

// prothero_robinson with its J_I hidden (the model has one): a split whose implicit part has no
// analytic Jacobian, forwarding f, J, the parts and the exact solution to the model's public calls.
class WithoutImplicitJacobian final : public OdeSystem {
 public:
  explicit WithoutImplicitJacobian(std::unique_ptr<OdeSystem> inner) : inner_(std::move(inner)) {}
  std::string name() const override { return inner_->name(); }
  Index dimension() const override { return inner_->dimension(); }
  Vec initial_state() const override { return inner_->initial_state(); }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { inner_->exact(t, y); }
  bool has_imex_split() const override { return true; }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef f) const override { inner_->rhs(t, y, f); }
  void eval_jacobian(double t, CVecRef y, SparseMat& j) const override {
    inner_->jacobian(t, y, j);
  }
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef f) const override {
    inner_->rhs_explicit_part(t, y, f);
  }
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef f) const override {
    inner_->rhs_implicit_part(t, y, f);
  }

 private:
  std::unique_ptr<OdeSystem> inner_;
};

// A split without J_I (prothero_robinson's f_I = lambda (y - phi(t)), f_E = phi'(t), its J_I
// hidden): the implicit sub-integrator runs finite-difference Jacobians inside its Newton
// iteration (which once overwrote the Newton residual: every such step failed). lambda = -10:
// J = lambda exactly, so sdirk3 with jacobian=fd_dense on the whole model matches the
// analytic-Jacobian run to the Newton tolerance, and strang's error at t = 1 falls by 4 per
// halving (order 2) from h = 0.025.
TEST(OperatorSplitting, RunsOnASplitWithoutImplicitJacobian) {
  auto pr = model("prothero_robinson", {"lambda=-10"});
  auto fd = make("sdirk3", {"jacobian=fd_dense"});
  auto an = make("sdirk3");
  const RunResult a = run_fixed_step(*pr, *fd, {1.0, 0.1});
  const RunResult b = run_fixed_step(*pr, *an, {1.0, 0.1});
  ASSERT_EQ(a.stats.status, Status::ok) << a.stats.message;
  ASSERT_EQ(b.stats.status, Status::ok) << b.stats.message;
  EXPECT_LT(max_abs_diff(a.y, b.y), 1e-10);
  std::vector<double> err;
  for (double h = 0.025; h > 0.003; h /= 2) {
    auto s = make("strang");
    WithoutImplicitJacobian split(model("prothero_robinson", {"lambda=-10"}));
    ASSERT_FALSE(split.has_implicit_part_jacobian());
    const RunResult r = run_fixed_step(split, *s, {1.0, h});
    ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
    Vec ye(1);
    pr->exact(1.0, ye);
    err.push_back(max_abs_diff(r.y, ye));
  }
  for (std::size_t k = 0; k + 1 < err.size(); ++k)
    EXPECT_NEAR(std::log2(err[k] / err[k + 1]), 2.0, 0.15) << err[k] << " -> " << err[k + 1];
}

}  // namespace
}  // namespace stiffbench

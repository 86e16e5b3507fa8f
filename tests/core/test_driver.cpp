// The fixed-step driver: step count rule, end time, observer, blow-up detection, counting.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

// N = round(T/h) steps of exactly T/N: h = 0.3 over [0, 1] gives 3 steps of 1/3, ending at 1.
TEST(Driver, StepCountRuleAndExactEndTime) {
  auto sys = model("harmonic_oscillator");
  auto rk = make("rk4");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 0.3;
  const RunResult r = run_fixed_step(*sys, *rk, opt);
  EXPECT_EQ(r.n_steps, 3);
  EXPECT_EQ(r.stats.steps, 3);
  EXPECT_DOUBLE_EQ(r.h, 1.0 / 3.0);
  EXPECT_EQ(r.t, 1.0);
  // A step larger than the interval still takes one step.
  opt.h = 5.0;
  EXPECT_EQ(run_fixed_step(*sys, *rk, opt).n_steps, 1);
}

TEST(Driver, ObserverAtEquallySpacedOutputs) {
  auto sys = model("harmonic_oscillator");
  auto rk = make("heun");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 0.01;
  opt.outputs = 10;
  std::vector<double> times;
  run_fixed_step(*sys, *rk, opt, [&](double t, CVecRef) { times.push_back(t); });
  ASSERT_EQ(times.size(), 11u);
  for (std::size_t j = 0; j < times.size(); ++j)
    EXPECT_NEAR(times[j], 0.1 * static_cast<double>(j), 1e-14);
  EXPECT_EQ(times.back(), 1.0);
}

// Explicit Euler on y' = λ(y - sin t) + cos t with λ = -1e6 and h = 0.1 amplifies errors by
// |1 + hλ| ≈ 1e5 per step: the run must end as `unstable`, not produce numbers.
TEST(Driver, BlowUpEndsRunAsUnstable) {
  auto sys = model("prothero_robinson", {"lambda=-1e6"});
  auto eu = make("euler");
  FixedStepOptions opt;
  opt.t_end = 10.0;
  opt.h = 0.1;
  const RunResult r = run_fixed_step(*sys, *eu, opt);
  EXPECT_EQ(r.stats.status, Status::unstable);
  EXPECT_LT(r.stats.steps, 100);
  EXPECT_NE(r.stats.message.find("blow-up"), std::string::npos);
}

class NanSystem final : public OdeSystem {
 public:
  std::string name() const override { return "nan"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }

 protected:
  void eval_rhs(double t, CVecRef, VecRef dydt) const override {
    dydt[0] = t > 0.25 ? std::numeric_limits<double>::quiet_NaN() : 0.0;
  }
};

TEST(Driver, NonFiniteStateIsUnstable) {
  NanSystem sys;
  auto eu = make("euler");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 0.1;
  const RunResult r = run_fixed_step(sys, *eu, opt);
  EXPECT_EQ(r.stats.status, Status::unstable);
  EXPECT_EQ(r.stats.steps, 4);  // the step from t = 0.3 evaluates f at t > 0.25
}

// A program's own system whose initial state does not have its dimension, or of dimension 0, is
// refused before anything is sized (it would otherwise read or write past the vectors).
class WrongSizeSystem final : public OdeSystem {
 public:
  WrongSizeSystem(Index dim, Index y0_size) : dim_(dim), y0_size_(y0_size) {}
  std::string name() const override { return "wrong_size"; }
  Index dimension() const override { return dim_; }
  Vec initial_state() const override { return Vec::Ones(y0_size_); }

 protected:
  void eval_rhs(double, CVecRef y, VecRef dydt) const override { dydt = -y; }

 private:
  Index dim_, y0_size_;
};

TEST(Driver, AStateOfAnotherSizeOrNoUnknownIsBadInput) {
  auto rk = make("rk4");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 0.1;
  for (const auto& [dim, size] : {std::pair<Index, Index>{3, 2}, {2, 3}, {0, 0}}) {
    const WrongSizeSystem sys(dim, size);
    try {
      run_fixed_step(sys, *rk, opt);
      ADD_FAILURE() << "dimension " << dim << ", initial state " << size << ": no BadInput";
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find("system 'wrong_size'"), std::string::npos) << e.what();
    }
  }
  auto dopri = make("dopri5");
  AdaptiveOptions aopt;
  aopt.t_end = 1.0;
  EXPECT_THROW(run_adaptive(WrongSizeSystem(3, 2), *dopri, aopt), BadInput);
  // The right size runs.
  EXPECT_EQ(run_fixed_step(WrongSizeSystem(2, 2), *rk, opt).stats.status, Status::ok);
}

TEST(Driver, BadStepOrEndTimeIsBadInput) {
  auto sys = model("harmonic_oscillator");
  auto rk = make("rk4");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 0.0;
  EXPECT_THROW(run_fixed_step(*sys, *rk, opt), BadInput);
  opt.h = -0.1;
  EXPECT_THROW(run_fixed_step(*sys, *rk, opt), BadInput);
  opt.h = 0.1;
  opt.t_end = 0.0;
  EXPECT_THROW(run_fixed_step(*sys, *rk, opt), BadInput);
  opt.t_end = 1.0;
  opt.h = 1e-12;
  opt.max_steps = 1000;
  EXPECT_THROW(run_fixed_step(*sys, *rk, opt), BadInput);
}

// f evaluations in the stats are the system's own counter over the run.
TEST(Driver, StatsCountEvaluationsAtTheBoundary) {
  auto sys = model("kepler");
  auto rk = make("rk38");
  sys->reset_counters();
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 0.01;
  const RunResult r = run_fixed_step(*sys, *rk, opt);
  EXPECT_EQ(r.stats.f_evals, sys->counters().f_evals);
  EXPECT_EQ(r.stats.f_evals, 100 * 4);
}

// --- admissible set (OdeSystem::nonnegative_components) ----------------------------------------

// y' = -k y, y(0) = 1, declared non-negative (its solution e^{-kt} is, by the positivity criterion
// of core/ode_system.hpp: f = 0 at y = 0).
class NonNegativeDecay final : public OdeSystem {
 public:
  explicit NonNegativeDecay(double k) : k_(k) {}
  std::string name() const override { return "nonnegative_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  std::vector<Index> nonnegative_components() const override { return {0}; }

 protected:
  void eval_rhs(double, CVecRef y, VecRef dydt) const override { dydt = -k_ * y; }

 private:
  double k_;
};

// Explicit Euler at hk = 1.5 multiplies y by R(-1.5) = 1 + (-1.5) = -0.5 per step: the state
// alternates in sign while it decays (|R| < 1: not unstable). The driver checks the admissible set
// at output steps only, with the fixed-step bound 1e-8·max(1, ‖y‖∞) = 1e-8.
TEST(Driver, FixedStepStateBelowZeroAtAnOutputIsInvalidState) {
  const NonNegativeDecay sys(10.0);
  auto eu = make("euler");
  FixedStepOptions opt;
  opt.h = 0.15;
  // Two steps and only the final state checked: y = 0.25 is admissible.
  opt.t_end = 0.3;
  EXPECT_EQ(run_fixed_step(sys, *eu, opt).stats.status, Status::ok);
  // Three steps: y = -0.125 at t = 0.45.
  opt.t_end = 0.45;
  RunResult r = run_fixed_step(sys, *eu, opt);
  EXPECT_EQ(r.stats.status, Status::invalid_state);
  EXPECT_EQ(r.stats.steps, 3);
  EXPECT_NE(r.stats.message.find("y[0] = -0.125 < -1e-08 at t = 0.45"), std::string::npos)
      << r.stats.message;
  EXPECT_EQ(to_string(r.stats.status), "invalid_state");
  // Every step an output: the run ends after the first, at y = -0.5.
  opt.outputs = 3;
  r = run_fixed_step(sys, *eu, opt);
  EXPECT_EQ(r.stats.status, Status::invalid_state);
  EXPECT_EQ(r.stats.steps, 1);
  EXPECT_NEAR(r.y[0], -0.5, 1e-15);
  EXPECT_NE(r.stats.message.find("y[0] = -0.5 < -1e-08 at t = 0.15"), std::string::npos)
      << r.stats.message;
}

// y' = -1, y(0) = 1 with a non-negativity it does not have (y = 1 - t): the driver trusts the
// declaration, which makes the bound of an adaptive run visible. dopri5 integrates y = 1 - t
// exactly (to round-off), so at t = 1.0005 the state is -5e-4: admissible under atol = 1e-3,
// not under atol = 1e-4 (the bound of an adaptive run is the method's atol).
class LinearDescent final : public OdeSystem {
 public:
  std::string name() const override { return "linear_descent"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  std::vector<Index> nonnegative_components() const override { return {0}; }

 protected:
  void eval_rhs(double, CVecRef, VecRef dydt) const override { dydt[0] = -1.0; }
};

TEST(Driver, AdaptiveBoundIsTheMethodsAtol) {
  const LinearDescent sys;
  AdaptiveOptions opt;
  opt.t_end = 2.0;
  opt.times = {1.0005, 2.0};
  auto loose = make("dopri5", {"atol=1e-3"});
  RunResult r = run_adaptive(sys, *loose, opt);
  EXPECT_EQ(r.stats.status, Status::invalid_state);
  EXPECT_EQ(r.t, 2.0) << r.stats.message;  // passed the check at t = 1.0005
  EXPECT_NE(r.stats.message.find("< -0.001 at t = 2"), std::string::npos) << r.stats.message;
  auto tight = make("dopri5", {"atol=1e-4"});
  r = run_adaptive(sys, *tight, opt);
  EXPECT_EQ(r.stats.status, Status::invalid_state);
  EXPECT_EQ(r.t, 1.0005);
  EXPECT_NEAR(r.y[0], -5e-4, 1e-14);
  EXPECT_NE(r.stats.message.find("< -0.0001 at t = 1.0005"), std::string::npos) << r.stats.message;
}

}  // namespace
}  // namespace stiffbench

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

}  // namespace
}  // namespace stiffbench

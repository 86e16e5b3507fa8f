// Stopping runs from outside (core/run_control.hpp): a wall-clock limit per row ends that row
// with status timeout while the study goes on, and an interrupt request unwinds out of every
// kind of run (the command line's SIGINT/SIGTERM exits: tests/cli/test_run_control_cli.cpp).
// Library references (SUNDIALS, GSL) are stopped
// through their C callbacks like the hand-written methods, and a model that throws inside them
// ends the run with status error.
//
// No assertion here is on speed: the limits are far from the work the runs need (a run of
// milliseconds under a limit of seconds, a run of minutes over it), so a loaded machine changes
// only how long the test takes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/driver.hpp"
#include "core/run_control.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/studies/convergence.hpp"
#include "experiments/studies/stability.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;
using namespace stiffbench;
using stiffbench::testing_support::make;

namespace {

// y' = -y, y(0) = 1 (exact e^{-t}), with an optional pause in every evaluation and an optional
// action at one chosen evaluation.
class SlowDecay final : public OdeSystem {
 public:
  explicit SlowDecay(std::chrono::microseconds pause = {}) : pause_(pause) {}
  std::string name() const override { return "slow_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-t); }
  bool autonomous() const override { return true; }

  long act_at = -1;
  enum class Act { none, interrupt, fail } act = Act::none;

 protected:
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    f[0] = -y[0];
    if (pause_.count() > 0) std::this_thread::sleep_for(pause_);
    if (++evals_ != act_at) return;
    if (act == Act::interrupt) request_interrupt(SIGINT);
    if (act == Act::fail) throw std::runtime_error("model failure injected by the test");
  }

 private:
  std::chrono::microseconds pause_;
  mutable long evals_ = 0;
};

// Sets the process-wide limit for one test and restores "none" afterwards.
struct WallLimit {
  explicit WallLimit(double s) { set_wall_limit(s); }
  ~WallLimit() { set_wall_limit(0); }
};

// --- wall-clock limit -------------------------------------------------------------------------

// 1000 steps of rk4 with a 1 ms pause per evaluation need at least 4 s; the limit is 0.3 s.
TEST(RunControl, RowOverItsWallLimitEndsWithTimeoutAndTheNextRowRuns) {
  const WallLimit limit(0.3);
  const long faults = fault_count();
  SlowDecay slow(std::chrono::milliseconds(1));
  auto rk4 = make("rk4");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 1e-3;
  const RunResult r = run_fixed_step(slow, *rk4, opt);
  EXPECT_EQ(r.stats.status, Status::timeout);
  EXPECT_NE(r.stats.message.find("--max-wall"), std::string::npos) << r.stats.message;
  EXPECT_LT(r.t, opt.t_end);             // stopped early...
  EXPECT_GE(r.stats.wall_s, 0.3);        // ...but not before the limit
  EXPECT_EQ(fault_count(), faults + 1);  // a failed row for the exit code

  // The next row has its own clock: 100 steps without a pause finish far inside the limit. The
  // bound is rk4's global error on y' = -y, t·e^{-t}·h⁴/120 ≈ 3e-11 at t = 1, h = 0.01 (the
  // leading term of (e^{-h} - R(-h))/h per unit time, R the degree-4 Taylor polynomial), with a
  // margin of 30.
  SlowDecay fast;
  const RunResult ok = run_fixed_step(fast, *rk4, {1.0, 0.01});
  ASSERT_EQ(ok.stats.status, Status::ok) << ok.stats.message;
  EXPECT_NEAR(ok.y[0], std::exp(-1.0), 1e-9);
}

// A timeout the caller planned for (recommend's budget shares) ends the run the same way but is
// not a fault; the scope restores counting when it ends.
TEST(RunControl, ExpectedTimeoutsAreNotFaults) {
  SlowDecay slow(std::chrono::milliseconds(1));
  auto rk4 = make("rk4");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 1e-3;
  const long faults = fault_count();
  {
    const ExpectedTimeouts planned;
    const RowClock clock(0.05);
    const RunResult r = run_fixed_step(slow, *rk4, opt);
    EXPECT_EQ(r.stats.status, Status::timeout);
    EXPECT_LT(r.t, opt.t_end);
  }
  EXPECT_EQ(fault_count(), faults);
  {
    const RowClock clock(0.05);
    EXPECT_EQ(run_fixed_step(slow, *rk4, opt).stats.status, Status::timeout);
  }
  EXPECT_EQ(fault_count(), faults + 1);
}

// The library references are stopped through their C callbacks (the exception is kept there and
// rethrown when the library returns), and so is an adaptive hand-written method.
TEST(RunControl, AdaptiveAndLibraryRunsTimeOut) {
  const WallLimit limit(0.2);
  for (const char* name : {"cvode_bdf", "arkode_erk", "gsl_rkf45", "gsl_msbdf", "dopri5"}) {
    SlowDecay slow(std::chrono::milliseconds(1));
    // rtol 1e-12 over [0, 100] needs thousands of evaluations: at least several seconds.
    auto integ = make(name, {"rtol=1e-12", "atol=1e-14"});
    const RunResult r = run_adaptive(slow, *integ, {100.0, 0});
    EXPECT_EQ(r.stats.status, Status::timeout) << name << ": " << r.stats.message;
    EXPECT_NE(r.stats.message.find("--max-wall"), std::string::npos) << name;
  }
}

// A row made of several runs (a stability bisection) opens one clock around them all: the
// driver's runs inside it share it instead of restarting it.
TEST(RunControl, NestedRunsShareTheRowClock) {
  SlowDecay fast;
  auto rk4 = make("rk4");
  {
    const RowClock row(0.05);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the row's time is used up
    EXPECT_TRUE(RowClock::expired());
    const RunResult r = run_fixed_step(fast, *rk4, {1.0, 1e-3});
    EXPECT_EQ(r.stats.status, Status::timeout) << r.stats.message;
  }
  // Without the row around it, the same run has its own clock (and no limit is set here).
  EXPECT_FALSE(RowClock::expired());
  EXPECT_EQ(run_fixed_step(fast, *rk4, {1.0, 1e-3}).stats.status, Status::ok);
}

// A stability row whose bisection passes the limit is reported as timeout, not as a limit: a
// probe stopped by the clock says nothing about stability (counting it as unstable would give a
// wrong, smaller h_max). With a limit of 1 ns the first probe's first clock reading is over it.
TEST(RunControl, StabilityRowOverTheLimitIsTimeoutNotAStepLimit) {
  StabilitySpec spec;
  spec.model = "spring_chain";
  spec.integrators = {"symplectic_euler"};
  StabilityResult r;
  {
    const WallLimit limit(1e-9);
    r = run_stability(spec, nullptr);
  }
  ASSERT_EQ(r.rows.size(), 1u);
  EXPECT_EQ(r.rows[0].status, "timeout");
  EXPECT_FALSE(r.rows[0].h_measured);
  EXPECT_NE(r.rows[0].message.find("--max-wall"), std::string::npos) << r.rows[0].message;
}

TEST(RunControl, WallLimitMustBeAFiniteNonNegativeNumber) {
  EXPECT_THROW(set_wall_limit(-1), BadInput);
  EXPECT_THROW(set_wall_limit(std::nan("")), BadInput);
  EXPECT_THROW(set_wall_limit(HUGE_VAL), BadInput);
  EXPECT_DOUBLE_EQ(wall_limit(), 0.0);
}

// --- interrupts -------------------------------------------------------------------------------

// An interrupt requested in the middle of a run (here by the model itself, at its 50th
// evaluation) unwinds out of the driver as Interrupted, also across the C libraries; the
// integrator can be reset and run again afterwards.
TEST(RunControl, InterruptUnwindsOutOfEveryKindOfRun) {
  for (const char* name : {"rk4", "dopri5", "radau5", "cvode_bdf", "arkode_dirk", "gsl_msbdf"}) {
    SlowDecay sys;
    sys.act = SlowDecay::Act::interrupt;
    sys.act_at = 50;
    auto integ = make(name, {"rtol=1e-10", "atol=1e-12"});
    const bool adaptive = integ->supports_adaptive();
    bool interrupted = false;
    try {
      if (adaptive)
        run_adaptive(sys, *integ, {10.0, 0});
      else
        run_fixed_step(sys, *integ, {10.0, 1e-3});
    } catch (const Interrupted& i) {
      interrupted = true;
      EXPECT_EQ(i.signal, SIGINT);
    }
    EXPECT_TRUE(interrupted) << name;
    EXPECT_EQ(interrupt_requested(), SIGINT);
    clear_interrupt();
    SlowDecay again;
    const RunResult r = adaptive ? run_adaptive(again, *integ, {1.0, 0})
                                 : run_fixed_step(again, *integ, {1.0, 1e-3});
    ASSERT_EQ(r.stats.status, Status::ok) << name << ": " << r.stats.message;
    // A real result after the reset: the adaptive runs at rtol 1e-10 and rk4 at h = 1e-3
    // (global error ~3e-15, as above) are all far inside 1e-6 of the exact e^{-1}.
    EXPECT_NEAR(r.y[0], std::exp(-1.0), 1e-6) << name;
  }
}

// A model that throws inside a library reference ends the run with status error and the model's
// message, as it does under a hand-written method (before, SUNDIALS reported solver_error and
// GSL let the exception cross its C frames).
TEST(RunControl, ModelThrowingInsideALibraryIsStatusError) {
  for (const char* name : {"cvode_bdf", "arkode_erk", "gsl_rkf45", "gsl_msbdf"}) {
    SlowDecay sys;
    sys.act = SlowDecay::Act::fail;
    sys.act_at = 30;
    auto integ = make(name, {"rtol=1e-10", "atol=1e-12"});
    const RunResult r = run_adaptive(sys, *integ, {10.0, 0});
    EXPECT_EQ(r.stats.status, Status::error) << name << ": " << r.stats.message;
    EXPECT_NE(r.stats.message.find("model failure injected"), std::string::npos)
        << name << ": " << r.stats.message;
  }
}

}  // namespace

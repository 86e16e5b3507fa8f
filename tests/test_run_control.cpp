// Stopping runs from outside (issue 14, core/run_control.hpp): a wall-clock limit per row ends
// that row with status timeout while the study goes on, and SIGINT/SIGTERM stop the command with
// exit 130/143 leaving complete files only. Library references (SUNDIALS, GSL) are stopped
// through their C callbacks like the hand-written methods, and a model that throws inside them
// ends the run with status error.
//
// No assertion here is on speed: the limits are far from the work the runs need (a run of
// milliseconds under a limit of seconds, a run of minutes over it), so a loaded machine changes
// only how long the test takes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
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
#include "experiments/catalog.hpp"
#include "experiments/convergence.hpp"
#include "experiments/stability.hpp"
#include "test_support.hpp"
#include "tests/cli_support.hpp"

extern char** environ;

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

// --- the command line -------------------------------------------------------------------------

struct Child {
  pid_t pid = -1;
  fs::path out, err;
};

// Starts the real binary with stdout and stderr sent to files (no shell in between, so signals
// reach stiffbench itself).
Child spawn(const std::vector<std::string>& args, const fs::path& dir) {
  Child c;
  c.out = dir / "stdout.txt";
  c.err = dir / "stderr.txt";
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, c.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, c.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> all = {STIFFBENCH_BIN};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  if (posix_spawn(&c.pid, STIFFBENCH_BIN, &fa, nullptr, argv.data(), environ) != 0) c.pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return c;
}

int wait_exit(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1000 + WTERMSIG(status);
}

using stiffbench::testing_support::slurp;

// Waits (up to two minutes) until `file` holds `needle` `times` times.
bool wait_for(const fs::path& file, const std::string& needle, long times = 1) {
  for (int i = 0; i < 12000; ++i) {
    const std::string text = slurp(file);
    long n = 0;
    for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
    if (n >= times) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

std::vector<fs::path> temporaries(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().string().find(".tmp") != std::string::npos) out.push_back(e.path());
  return out;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = stiffbench::testing_support::fresh_dir("run_control", name);
  fs::create_directories(d);
  return d;
}

// A sweep of 24 units of about 0.1 s each (rk4 on the oscillator, 2·10⁶ steps): SIGINT while it
// runs leaves the units completed so far as whole CSV lines, exit code 130, no temporaries; a
// --resume run then finishes the others.
TEST(RunControlCli, SigintDuringASweepKeepsCompleteUnitsAndResumeFinishes) {
  const fs::path d = fresh_dir("sweep");
  std::ofstream(d / "spec.toml") << "kind = \"convergence\"\n"
                                    "model = \"harmonic_oscillator\"\n"
                                    "integrators = [\"rk4\"]\n"
                                    "t_end = 1.0\nh = 1e-6\nlevels = 2\nrefine = 2\n"
                                    "reference = \"exact\"\n"
                                    "[params]\n"
                                    "k = [1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7, 1.8, 1.9, 2.0, "
                                    "2.1, 2.2, 2.3, 2.4, 2.5, 2.6, 2.7, 2.8, 2.9, 3.0, 3.1, 3.2, "
                                    "3.3]\n";
  const fs::path out = d / "out";
  Child c = spawn({"run", (d / "spec.toml").string(), "--out", out.string()}, d);
  ASSERT_GT(c.pid, 0);
  // Two units (two rows each) are in the CSV, whose lines are flushed as units finish.
  ASSERT_TRUE(wait_for(out / "convergence.csv", "\n", 5)) << slurp(c.err);
  ::kill(c.pid, SIGINT);
  EXPECT_EQ(wait_exit(c.pid), 130) << slurp(c.err);
  const std::string err = slurp(c.err);
  EXPECT_NE(err.find("interrupted by SIGINT"), std::string::npos) << err;
  EXPECT_NE(err.find("--resume"), std::string::npos) << err;
  EXPECT_TRUE(temporaries(d).empty());

  // Every line of the CSV is complete: it ends with a newline and has the header's field count
  // (no field of these rows holds a comma); the header and at least two units (of 2 rows each).
  const std::string csv = slurp(out / "convergence.csv");
  ASSERT_FALSE(csv.empty());
  EXPECT_EQ(csv.back(), '\n');
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  const auto fields = std::count(line.begin(), line.end(), ',');
  int rows = 0;
  while (std::getline(lines, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), fields) << line;
    ++rows;
  }
  EXPECT_GE(rows, 4);
  EXPECT_LT(rows, 48);  // interrupted before the end

  Child resume = spawn({"run", (d / "spec.toml").string(), "--out", out.string(), "--resume"}, d);
  ASSERT_GT(resume.pid, 0);
  EXPECT_EQ(wait_exit(resume.pid), 0) << slurp(resume.err);
  const std::string full = slurp(out / "convergence.csv");
  EXPECT_EQ(std::count(full.begin(), full.end(), '\n'), 1 + 48);
  EXPECT_EQ(full.rfind(csv.substr(0, csv.find('\n')), 0), 0u);  // same header
  fs::remove_all(d);
}

// SIGTERM during a one-off study: exit 143, and the study's files are not written half-way (its
// table holds all rows or does not exist); the output folder it created is removed when empty.
TEST(RunControlCli, SigtermDuringAStudyExits143WithoutPartialFiles) {
  const fs::path d = fresh_dir("study");
  const fs::path out = d / "out";
  // Level 1 (10⁵ steps) finishes at once; level 3 (9·10⁷ steps) takes seconds.
  Child c =
      spawn({"convergence", "--model", "harmonic_oscillator", "--integrators", "rk4", "--t-end",
             "100", "--h", "1e-3", "--levels", "3", "--refine", "30", "--out", out.string()},
            d);
  ASSERT_GT(c.pid, 0);
  ASSERT_TRUE(wait_for(c.err, "[1/3]")) << slurp(c.err);
  ::kill(c.pid, SIGTERM);
  const int code = wait_exit(c.pid);
  if (code == 0) GTEST_SKIP() << "the study finished before the signal arrived";
  EXPECT_EQ(code, 143) << slurp(c.err);
  EXPECT_NE(slurp(c.err).find("interrupted by SIGTERM"), std::string::npos) << slurp(c.err);
  EXPECT_FALSE(fs::exists(out / "convergence.csv"));
  EXPECT_FALSE(fs::exists(out));  // created by this run, left empty, removed
  EXPECT_TRUE(temporaries(d).empty());
  fs::remove_all(d);
}

// --max-wall on the command line: the row over the limit is written with status timeout, the
// rows before it are real results, and the exit code is 3 (a row failed).
TEST(RunControlCli, MaxWallWritesATimeoutRowAndExitsThree) {
  const fs::path d = fresh_dir("maxwall");
  const fs::path out = d / "out";
  // h = 0.1 and 0.1/3000 take 100 and 3·10⁵ steps (milliseconds, far inside 2 s even under
  // the sanitizers); 0.1/3000² takes 9·10⁸ (tens of seconds).
  Child c = spawn(
      {"convergence", "--model", "harmonic_oscillator", "--integrators", "rk4", "--t-end", "10",
       "--h", "0.1", "--levels", "3", "--refine", "3000", "--max-wall", "2", "--out", out.string()},
      d);
  ASSERT_GT(c.pid, 0);
  EXPECT_EQ(wait_exit(c.pid), 3) << slurp(c.err);
  EXPECT_NE(slurp(c.err).find("timeout"), std::string::npos) << slurp(c.err);
  std::istringstream csv(slurp(out / "convergence.csv"));
  std::string header, line;
  std::getline(csv, header);
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_NE(rows[0].find(",ok"), std::string::npos) << rows[0];
  EXPECT_NE(rows[1].find(",ok"), std::string::npos) << rows[1];
  EXPECT_NE(rows[2].find(",timeout"), std::string::npos) << rows[2];
  fs::remove_all(d);
}

}  // namespace

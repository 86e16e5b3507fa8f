// Implicit solves on `cloth` n = 64 (4,096 points, top edge pinned, no damping), h = 0.01, the
// workload of the summary's target table:
//   implicit/plain_bw/cloth:64/omp:<t>   the plain Baraff–Witkin step (plain_cloth.hpp), CG at
//       relative 1e-6: one iteration = the 50 steps from t = 0 to 0.5 (warm start reset at t = 0),
//       counters s/step, assembly and CG seconds per step, CG iterations per step;
//   implicit/baraff_witkin/cloth:64/omp:2   the testbed's baraff_witkin with its defaults through
//       the fixed-step driver over the same 50 steps (one iteration = one run);
//   implicit/baraff_witkin_cg/cloth:64/omp:2   the same with linear_solver=cg, krylov_tol=1e-6;
//   implicit/backward_euler/cloth:64/omp:2  backward_euler (defaults), one step per iteration after
//       an untimed first step (as step/… in bench_steps.cpp);
//   implicit/cvode_bdf/cloth:64/omp:2   cvode_bdf with its defaults (linear_solver=auto: velocity
//   on the cloth) to t = 0.5 in a child
//       process (killed after Config::cvode_timeout_s: KLU on the 2n system did not finish), timed
//       by the library run's own wall time; counters steps and s/step = wall / steps;
//   check/bw_trajectory/cloth:64   not a timing: max |x| differences at t = 0.5 between the
//       plain step (CG 1e-6, and CG 1e-12) and the testbed's baraff_witkin runs above.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "bench/bench_common.hpp"
#include "bench/plain_cloth.hpp"
#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"

extern char** environ;

namespace stiffbench::bench {

void integrator_step(benchmark::State& st, long side, const std::string& name, const Params& params,
                     double h, int threads);

namespace {

constexpr long kSide = 64;
constexpr double kH = 0.01, kTEnd = 0.5;
constexpr long kSteps = 50;

std::map<std::string, Vec>& finals() {
  static std::map<std::string, Vec> f;
  return f;
}

const MassSpringNetwork& cloth64() {
  return dynamic_cast<const MassSpringNetwork&>(
      *cached_model("cloth", {{"n", std::to_string(kSide)}}).sys);
}

Vec run_plain(const MassSpringNetwork& net, PlainBaraffWitkin& bw, double* assembly, double* solve,
              long* iterations) {
  Vec y = net.initial_state();
  bw.reset();
  for (long k = 0; k < kSteps; ++k) {
    bw.step(y.data(), kH);
    if (assembly) *assembly += bw.last_assembly_s();
    if (solve) *solve += bw.last_solve_s();
    if (iterations) *iterations += bw.last_iterations();
  }
  return y;
}

void plain_bw(benchmark::State& st, int threads) {
  OmpThreads omp(threads);
  const MassSpringNetwork& net = cloth64();
  PlainBaraffWitkin bw(net, 1e-6);
  double assembly = 0.0, solve = 0.0;
  long iterations = 0;
  Vec y;
  for (auto _ : st) y = run_plain(net, bw, &assembly, &solve, &iterations);
  const double steps = static_cast<double>(kSteps * st.iterations());
  finals()["plain_bw"] = y;
  st.counters["s/step"] =
      benchmark::Counter(steps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  st.counters["assembly_s/step"] = assembly / steps;
  st.counters["cg_s/step"] = solve / steps;
  st.counters["cg_iters/step"] = static_cast<double>(iterations) / steps;
  st.counters["free_points"] = static_cast<double>(bw.free_points());
  st.counters["threads"] = threads;
}

void testbed_bw_run(benchmark::State& st, const std::string& key, const Params& params,
                    int threads) {
  OmpThreads omp(threads);
  const MassSpringNetwork& net = cloth64();
  std::unique_ptr<Integrator> integ;
  try {
    integ = integrator_registry().create("baraff_witkin", params);
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return;
  }
  FixedStepOptions opt;
  opt.t_end = kTEnd;
  opt.h = kH;
  RunResult r;
  long krylov = 0;
  for (auto _ : st) {
    try {
      r = run_fixed_step(net, *integ, opt);
    } catch (const std::exception& e) {
      st.SkipWithError(e.what());
      break;
    }
    if (r.stats.status != Status::ok) {
      st.SkipWithError((to_string(r.stats.status) + ": " + r.stats.message).c_str());
      break;
    }
    krylov += r.stats.linear_iters;
  }
  if (st.error_occurred()) return;
  finals()[key] = r.y;
  const double steps = static_cast<double>(kSteps * st.iterations());
  st.counters["s/step"] =
      benchmark::Counter(steps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  if (krylov > 0) st.counters["krylov/step"] = static_cast<double>(krylov) / steps;
  st.counters["threads"] = threads;
}

// Runs `args` (argv[0] first) with stdout captured; kills it after timeout_s. Returns whether
// it finished, with its stdout.
bool run_child(const std::vector<std::string>& args, double timeout_s, int threads,
               std::string& out) {
  int fds[2];
  if (pipe(fds) != 0) return false;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&fa, fds[0]);
  posix_spawn_file_actions_addclose(&fa, fds[1]);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::vector<std::string> env_store;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "OMP_NUM_THREADS=", 16) != 0) env_store.emplace_back(*e);
  env_store.push_back("OMP_NUM_THREADS=" + std::to_string(threads));
  std::vector<char*> envp;
  for (auto& e : env_store) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, "/proc/self/exe", &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    return false;
  }
  const double deadline = now_seconds() + timeout_s;
  bool finished = false;
  char buf[4096];
  for (;;) {
    const double left = deadline - now_seconds();
    if (left <= 0) break;
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::min(left, 1.0) * 1000) + 1);
    if (ready < 0) break;
    if (ready == 0) continue;
    const ssize_t got = read(fds[0], buf, sizeof buf);
    if (got <= 0) {
      finished = true;  // EOF: the child closed its stdout (exited)
      break;
    }
    out.append(buf, static_cast<std::size_t>(got));
  }
  close(fds[0]);
  if (!finished) kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  return finished && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

void cvode_run(benchmark::State& st, double timeout_s, int threads) {
  for (auto _ : st) {
    std::string out;
    const double start = now_seconds();
    const bool ok = run_child(
        {"stiffbench_bench", "--cvode-child", std::to_string(kSide), std::to_string(kTEnd), "auto"},
        timeout_s, threads, out);
    const double total = now_seconds() - start;
    std::istringstream in(out);
    std::string tag, status;
    double wall = 0.0;
    long steps = 0, f_evals = 0, jac_evals = 0;
    in >> tag >> wall >> steps >> f_evals >> jac_evals >> status;
    if (!ok || tag != "ok") {
      std::ostringstream msg;
      if (total >= timeout_s)
        msg << "no result within " << timeout_s << " s (killed)";
      else
        msg << "child failed: " << out;
      st.SkipWithError(msg.str().c_str());
      break;
    }
    if (status != "ok") {
      st.SkipWithError(("cvode_bdf status " + status).c_str());
      break;
    }
    st.SetIterationTime(wall);
    st.counters["steps"] = static_cast<double>(steps);
    st.counters["s/step"] = steps > 0 ? wall / static_cast<double>(steps) : 0.0;
    st.counters["f_evals"] = static_cast<double>(f_evals);
    st.counters["jac_evals"] = static_cast<double>(jac_evals);
    st.counters["process_s"] = total;
  }
}

void trajectory_check(benchmark::State& st) {
  const MassSpringNetwork& net = cloth64();
  const Index n = net.dofs();
  PlainBaraffWitkin tight(net, 1e-12);
  Vec y_tight;
  for (auto _ : st) y_tight = run_plain(net, tight, nullptr, nullptr, nullptr);
  auto diff = [&](const Vec& a, const Vec& b) {
    return (a.head(n) - b.head(n)).cwiseAbs().maxCoeff();
  };
  const auto& f = finals();
  // -1: the run it needs is missing (filtered out or failed).
  auto get = [&](const std::string& a, const std::string& b) {
    const auto ia = f.find(a), ib = f.find(b);
    return ia == f.end() || ib == f.end() ? -1.0 : diff(ia->second, ib->second);
  };
  st.counters["plain_vs_bw"] = get("plain_bw", "baraff_witkin");
  st.counters["plain_vs_bw_cg"] = get("plain_bw", "baraff_witkin_cg");
  const auto ib = f.find("baraff_witkin");
  st.counters["plain_tight_vs_bw"] = ib == f.end() ? -1.0 : diff(y_tight, ib->second);
  const auto ip = f.find("plain_bw");
  st.counters["plain_vs_plain_tight"] = ip == f.end() ? -1.0 : diff(y_tight, ip->second);
}

}  // namespace

int cvode_child_main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: stiffbench_bench --cvode-child SIDE T_END LINEAR_SOLVER\n");
    return 2;
  }
  try {
    Params mp;
    mp.set("n", argv[2]);
    const auto sys = model_registry().create("cloth", mp);
    Params ip;
    ip.set("linear_solver", argv[4]);
    const auto integ = integrator_registry().create("cvode_bdf", ip);
    AdaptiveOptions opt;
    opt.t_end = std::stod(argv[3]);
    const RunResult r = run_adaptive(*sys, *integ, opt);
    std::printf("ok %.9g %ld %ld %ld %s\n", r.stats.wall_s, r.stats.steps, r.stats.f_evals,
                r.stats.jac_evals, to_string(r.stats.status).c_str());
  } catch (const std::exception& e) {
    std::printf("error %s\n", e.what());
  }
  return 0;
}

void register_implicit_benchmarks(const Config& cfg) {
  const std::string c = "/cloth:" + std::to_string(kSide);
  for (const int t : {1, 2})
    add("implicit/plain_bw" + c + "/omp:" + std::to_string(t),
        [t](benchmark::State& st) { plain_bw(st, t); });
  // No iteration caps: a run or step slower than the minimum time (0.1 s with --quick) is
  // measured once (Google Benchmark's first trial runs one iteration), so today's slow solvers
  // cost one run each.
  // The testbed's rows at 1 thread as well: on a loaded machine the 1-thread ratios are the
  // less distorted ones.
  for (const int t : {1, 2})
    add("implicit/baraff_witkin" + c + "/omp:" + std::to_string(t), [t](benchmark::State& st) {
      testbed_bw_run(st, t == 2 ? "baraff_witkin" : "baraff_witkin_1", Params{}, t);
    });
  Params cg;
  cg.set("linear_solver", "cg");
  cg.set("krylov_tol", "1e-6");
  add("implicit/baraff_witkin_cg" + c + "/omp:2",
      [cg](benchmark::State& st) { testbed_bw_run(st, "baraff_witkin_cg", cg, 2); });
  for (const int t : {1, 2})
    add("implicit/backward_euler" + c + "/omp:" + std::to_string(t), [t](benchmark::State& st) {
      integrator_step(st, kSide, "backward_euler", Params{}, kH, t);
    });
  const double timeout = cfg.cvode_timeout_s;
  benchmark::RegisterBenchmark(("implicit/cvode_bdf" + c + "/omp:2").c_str(),
                               [timeout](benchmark::State& st) { cvode_run(st, timeout, 2); })
      ->UseManualTime()
      ->Iterations(1)
      ->Unit(benchmark::kMillisecond);
  add("check/bw_trajectory" + c, [](benchmark::State& st) { trajectory_check(st); })->Iterations(1);
}

}  // namespace stiffbench::bench

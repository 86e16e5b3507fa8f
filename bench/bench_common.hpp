// Shared pieces of the stiffbench_bench program: run configuration, a model cache (building a
// 512² cloth or a 1e5-particle SPH scene takes seconds, and Google Benchmark calls a benchmark
// function once per trial iteration count), thread control and small timing helpers.
//
// Benchmark names are paths: "<group>/<what>/<size>/omp:<threads>", e.g.
// "rhs/cloth/n:512/omp:2". The summary (summary.cpp) looks results up by these exact names, so
// every figure it prints is a ratio of two measurements from the same run.
#pragma once

#include <benchmark/benchmark.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bench/cpu_speed.hpp"
#include "core/ode_system.hpp"
#include "core/params.hpp"

namespace stiffbench {
class Integrator;
}

namespace stiffbench::bench {

struct Config {
  bool quick = false;
  // Seconds a CVODE child run may take before it is killed (its row then reports the limit).
  double cvode_timeout_s = 300.0;
  // Allocations the counter saw for one Eigen vector and one std::vector (expected: 2).
  long alloc_self_check = -1;
  // The CPUs' arithmetic rates just before and just after the benchmarks (cpu_speed.hpp).
  CpuSpeeds cpu_before, cpu_after;
};

// One measured benchmark as the summary sees it. With --benchmark_repetitions=N every
// repetition's real time per iteration is kept: `seconds` is their median, `min_seconds` the
// fastest, and [ci_low, ci_high] a bootstrap 95% interval of the median (timing_spread of
// experiments/support/timing.hpp: 2000 resamples, seeded by the benchmark's name, so the
// same times give the same interval; with 5 repetitions it spans the fastest to the slowest).
// `counters` are those of the repetition at the median (the lower middle one for an even N).
struct Result {
  double seconds = 0.0;  // real time per iteration: median over repetitions
  double min_seconds = 0.0, ci_low = 0.0, ci_high = 0.0;
  int repetitions = 0;
  std::vector<double> samples;  // each repetition's seconds, in run order
  long iterations = 0;
  std::map<std::string, double> counters;
  bool error = false;
  std::string message;
};
using Results = std::map<std::string, Result>;

// Fills seconds, min_seconds, ci_low, ci_high and repetitions of r from r.samples.
void summarise_repetitions(const std::string& name, Result& r);

// A model built once and kept while consecutive benchmarks use it (the cache holds the two most
// recently used models), with a "warm" state: the initial state, or for SPH scenes the state
// after some symplectic Euler steps at the suggested step (particles off their lattice).
struct CachedModel {
  std::unique_ptr<OdeSystem> sys;
  Vec warm;
};
const CachedModel& cached_model(const std::string& name,
                                const std::vector<std::pair<std::string, std::string>>& params,
                                int warm_steps = 0);

// Sets the OpenMP thread count for the benchmark's lifetime; restores the previous count.
class OmpThreads {
 public:
  explicit OmpThreads(int n);
  ~OmpThreads();
  OmpThreads(const OmpThreads&) = delete;
  OmpThreads& operator=(const OmpThreads&) = delete;

 private:
  int previous_;
};

// Best-of-reps seconds per call of f (each rep repeats f until it has run >= 2 ms).
double best_seconds_per_call(const std::function<void()>& f, int reps = 5);

double now_seconds();

// Wall time spent in each benchmark registered with add(), set-up and every trial run included
// (the summary lists the largest, to keep --quick under its budget).
std::map<std::string, double>& time_spent();

// Paired, interleaved timing: rounds of "time a, then time b" inside one benchmark, each side
// a block of work it times itself (after an untimed warm-up call of its own, so that neither
// side pays for the other's cache contents), and the per-round ratio time(a) / time(b). A
// drift of the machine's speed on the scale of seconds (the project's vCPUs: up to 0.6x for
// minutes) changes both sides of a round alike, where the ratio of
// two rows measured seconds apart takes it whole. Every round's ratio, over all repetitions,
// is kept under the benchmark's name for the summary (median and bootstrap interval).
std::map<std::string, std::vector<double>>& paired_ratios();
// One round per iteration of st; a() and b() return the seconds of their timed blocks. The
// counter "ratio" is the median over this repetition's rounds.
void paired_rounds(benchmark::State& st, const std::string& name, const std::function<double()>& a,
                   const std::function<double()>& b);

// One fixed-step driver run (run_fixed_step_from) of `steps` steps of h from (t, y), continuing
// there: t and y advance. Returns "" on success, else the run's message (t and y unchanged).
std::string driver_run(const OdeSystem& sys, Integrator& integ, double& t, Vec& y, double h,
                       long steps);

// Seconds that `count` calls of f take, after one untimed call (a side of a paired round).
double timed_calls(const std::function<void()>& f, int count);

// Registration helpers (benchmark::RegisterBenchmark with real time and a unit chosen from the
// expected magnitude).
benchmark::internal::Benchmark* add(const std::string& name,
                                    std::function<void(benchmark::State&)> fn,
                                    benchmark::TimeUnit unit = benchmark::kMillisecond);

void register_rhs_benchmarks(const Config& cfg);
void register_step_benchmarks(const Config& cfg);
void register_implicit_benchmarks(const Config& cfg);

// Summary of ratios printed after the table (summary.cpp).
void print_summary(const Results& r, const Config& cfg, double wall_seconds);

// Child mode of the binary (a CVODE run in its own process, so that a run that never finishes
// can be killed): prints "ok <wall_s> <steps> <f_evals> <jac_evals> <status>" and returns 0.
int cvode_child_main(int argc, char** argv);

}  // namespace stiffbench::bench

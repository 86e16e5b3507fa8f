// stiffbench_bench: the cost benchmarks in one Google Benchmark program, followed by
// a summary of ratios, each of two measurements from this same run (summary.cpp).
//
//   stiffbench_bench [--quick] [Google Benchmark flags]
//
// --quick runs a curated subset with --benchmark_min_time=0.1 (unless given) and a 20 s limit
// on the CVODE run, in under two minutes on the project's 2-core machine; without it every
// size and thread count runs at Google Benchmark's default minimum time and CVODE gets 300 s.
// Other flags go to Google Benchmark (--benchmark_filter=REGEX, --benchmark_repetitions=N, ...;
// version 1.7.1 takes --benchmark_min_time=SECONDS without a unit). Without
// --benchmark_repetitions a full run repeats every benchmark 5 times and --quick once; the
// summary uses the median repetition and lists each benchmark's median, minimum and bootstrap 95%
// interval of the median. Before and after the benchmarks it probes each CPU's arithmetic rate,
// alone and with all busy (cpu_speed.hpp): the summary prints it beside the 2-thread speed-ups.
// The binary also has a child mode, --cvode-child (bench_implicit.cpp).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "bench/alloc_count.hpp"
#include "bench/bench_common.hpp"

namespace {

using stiffbench::bench::Result;
using stiffbench::bench::Results;

// The console table as usual, plus every iteration run kept for the summary.
class CollectingReporter : public benchmark::ConsoleReporter {
 public:
  CollectingReporter() : benchmark::ConsoleReporter(OO_Tabular) {}

  void ReportRuns(const std::vector<Run>& reports) override {
    for (const Run& run : reports) {
      if (run.run_type != Run::RT_Iteration) continue;
      const std::string name = run.run_name.function_name;
      Result& r = results_[name];
      if (run.error_occurred && !r.error) {
        r.error = true;
        r.message = run.error_message;
      }
      if (run.error_occurred) continue;
      const double seconds = run.iterations > 0
                                 ? run.real_accumulated_time / static_cast<double>(run.iterations)
                                 : 0.0;
      r.samples.push_back(seconds);
      r.iterations = static_cast<long>(run.iterations);
      std::map<std::string, double> counters;
      for (const auto& [k, c] : run.counters) counters[k] = c.value;
      counters_[name].push_back(std::move(counters));
    }
    benchmark::ConsoleReporter::ReportRuns(reports);
  }

  // Medians and spread; the counters of the median repetition.
  void finish() {
    for (auto& [name, r] : results_) {
      if (r.error || r.samples.empty()) continue;
      summarise_repetitions(name, r);
      std::vector<std::size_t> order(r.samples.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::sort(order.begin(), order.end(),
                [&](std::size_t a, std::size_t b) { return r.samples[a] < r.samples[b]; });
      r.counters = counters_[name][order[(order.size() - 1) / 2]];
    }
  }

  const Results& results() const { return results_; }

 private:
  Results results_;
  std::map<std::string, std::vector<std::map<std::string, double>>> counters_;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace stiffbench::bench;
  if (argc > 1 && std::strcmp(argv[1], "--cvode-child") == 0) return cvode_child_main(argc, argv);
  Config cfg;
  std::vector<char*> args{argv[0]};
  bool min_time_given = false, repetitions_given = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      cfg.quick = true;
      continue;
    }
    if (std::strncmp(argv[i], "--benchmark_min_time", 20) == 0) min_time_given = true;
    if (std::strncmp(argv[i], "--benchmark_repetitions", 23) == 0) repetitions_given = true;
    args.push_back(argv[i]);
  }
  std::string min_time = "--benchmark_min_time=0.1";
  if (cfg.quick && !min_time_given) args.push_back(min_time.data());
  std::string repetitions = "--benchmark_repetitions=5";
  if (!cfg.quick && !repetitions_given) args.push_back(repetitions.data());
  cfg.cvode_timeout_s = cfg.quick ? 20.0 : 300.0;
  int ac = static_cast<int>(args.size());
  args.push_back(nullptr);
  benchmark::Initialize(&ac, args.data());
  if (benchmark::ReportUnrecognizedArguments(ac, args.data())) return 1;

  // The counter must see Eigen's allocations (malloc) as well as operator new.
  alloc_count_start();
  {
    stiffbench::Vec v(1000);
    std::vector<double> w(1000);
    benchmark::DoNotOptimize(v.data());
    benchmark::DoNotOptimize(w.data());
  }
  cfg.alloc_self_check = alloc_count_stop();

  register_rhs_benchmarks(cfg);
  register_step_benchmarks(cfg);
  register_implicit_benchmarks(cfg);

  const double start = now_seconds();
  cfg.cpu_before = measure_cpu_speeds();
  CollectingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.finish();
  cfg.cpu_after = measure_cpu_speeds();
  print_summary(reporter.results(), cfg, now_seconds() - start);
  benchmark::Shutdown();
  return 0;
}

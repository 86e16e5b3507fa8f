#include "bench/bench_common.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <deque>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/support/timing.hpp"

namespace stiffbench::bench {

namespace {

struct CacheEntry {
  std::string key;
  CachedModel model;
};

std::deque<CacheEntry>& cache() {
  static std::deque<CacheEntry> c;
  return c;
}

}  // namespace

const CachedModel& cached_model(const std::string& name,
                                const std::vector<std::pair<std::string, std::string>>& params,
                                int warm_steps) {
  std::string key = name;
  for (const auto& [k, v] : params) key += " " + k + "=" + v;
  key += " warm=" + std::to_string(warm_steps);
  auto& c = cache();
  for (auto it = c.begin(); it != c.end(); ++it) {
    if (it->key == key) {
      if (it != c.begin()) {
        CacheEntry e = std::move(*it);
        c.erase(it);
        c.push_front(std::move(e));
      }
      return c.front().model;
    }
  }
  // Keep at most two models alive (a 512² cloth holds ~0.4 GB of Jacobian pattern).
  while (c.size() >= 2) c.pop_back();
  Params p;
  for (const auto& [k, v] : params) p.set(k, v);
  CacheEntry e;
  e.key = key;
  e.model.sys = model_registry().create(name, p);
  e.model.warm = e.model.sys->initial_state();
  if (warm_steps > 0) {
    // Symplectic Euler at the suggested step: moves SPH particles off their initial lattice.
    const auto* mech = e.model.sys->as_mechanical();
    const Index n = mech->dofs();
    const double h = e.model.sys->suggested_step()->h;
    Vec a(n);
    Vec& y = e.model.warm;
    for (int k = 0; k < warm_steps; ++k) {
      mech->acceleration(0.0, y.head(n), y.tail(n), a);
      y.tail(n) += h * a;
      y.head(n) += h * y.tail(n);
    }
  }
  e.model.sys->reset_counters();
  c.push_front(std::move(e));
  return c.front().model;
}

OmpThreads::OmpThreads(int n) : previous_(omp_get_max_threads()) { omp_set_num_threads(n); }
OmpThreads::~OmpThreads() { omp_set_num_threads(previous_); }

void summarise_repetitions(const std::string& name, Result& r) {
  // FNV-1a of the name: each benchmark's bootstrap draws its own reproducible stream.
  std::uint64_t stream = 1469598103934665603ull;
  for (const unsigned char c : name) stream = (stream ^ c) * 1099511628211ull;
  const TimingSpread t = timing_spread(r.samples, 1, stream);
  r.seconds = t.median;
  r.min_seconds = t.min;
  r.ci_low = t.ci_low;
  r.ci_high = t.ci_high;
  r.repetitions = t.repeats;
}

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double best_seconds_per_call(const std::function<void()>& f, int reps) {
  double best = 1e300;
  for (int r = 0; r < reps; ++r) {
    const double t0 = now_seconds();
    long calls = 0;
    double t = t0;
    do {
      f();
      ++calls;
      t = now_seconds();
    } while (t - t0 < 2e-3);
    best = std::min(best, (t - t0) / static_cast<double>(calls));
  }
  return best;
}

std::map<std::string, std::vector<double>>& paired_ratios() {
  static std::map<std::string, std::vector<double>> r;
  return r;
}

void paired_rounds(benchmark::State& st, const std::string& name, const std::function<double()>& a,
                   const std::function<double()>& b) {
  std::vector<double> rounds;
  for (auto _ : st) {
    const double ta = a();
    const double tb = b();
    if (!(ta > 0.0 && tb > 0.0)) {
      st.SkipWithError("a paired block took no measurable time");
      return;
    }
    rounds.push_back(ta / tb);
  }
  if (rounds.empty()) return;
  auto& all = paired_ratios()[name];
  all.insert(all.end(), rounds.begin(), rounds.end());
  std::nth_element(rounds.begin(), rounds.begin() + static_cast<std::ptrdiff_t>(rounds.size() / 2),
                   rounds.end());
  st.counters["ratio"] = rounds[rounds.size() / 2];
}

std::string driver_run(const OdeSystem& sys, Integrator& integ, double& t, Vec& y, double h,
                       long steps) {
  FixedStepOptions opt;
  opt.h = h;
  opt.t_end = t + static_cast<double>(steps) * h;
  RunResult r = run_fixed_step_from(sys, integ, t, y, opt);
  if (r.stats.status != Status::ok) return r.stats.message.empty() ? "run failed" : r.stats.message;
  std::swap(y, r.y);
  t = r.t;
  return "";
}

double timed_calls(const std::function<void()>& f, int count) {
  f();
  const double t0 = now_seconds();
  for (int i = 0; i < count; ++i) f();
  return now_seconds() - t0;
}

std::map<std::string, double>& time_spent() {
  static std::map<std::string, double> t;
  return t;
}

benchmark::internal::Benchmark* add(const std::string& name,
                                    std::function<void(benchmark::State&)> fn,
                                    benchmark::TimeUnit unit) {
  return benchmark::RegisterBenchmark(name.c_str(),
                                      [name, fn = std::move(fn)](benchmark::State& s) {
                                        const double t0 = now_seconds();
                                        fn(s);
                                        time_spent()[name] += now_seconds() - t0;
                                      })
      ->UseRealTime()
      ->Unit(unit);
}

}  // namespace stiffbench::bench

#include "bench/cpu_speed.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

namespace stiffbench::bench {

namespace {

// Eight independent multiply-add chains (x <- x a + b, a fixed point that never overflows): the
// rate of the floating-point units, free of memory traffic. Returns chunks (100000 x 8
// multiply-adds) done per second.
// Starts once `starters` threads have incremented `start` (every thread pinned and ready).
double arithmetic_rate(double seconds, std::atomic<int>& start, int starters) {
  start.fetch_add(1);
  while (start.load() < starters) std::this_thread::yield();
  std::array<double, 8> x{};
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = 1.0 + 1e-3 * static_cast<double>(k);
  const double a = 0.999999, b = 1e-6;
  const auto t0 = std::chrono::steady_clock::now();
  long chunks = 0;
  double elapsed = 0.0;
  do {
    for (int i = 0; i < 100000; ++i)
      for (double& v : x) v = v * a + b;
    ++chunks;
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (elapsed < seconds);
  double sum = 0.0;
  for (double v : x) sum += v;
  // Keeps the loop (sum is about 8, never negative).
  if (sum < 0.0) std::printf("%g\n", sum);
  return static_cast<double>(chunks) / elapsed;
}

bool pin(pthread_t thread, int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(thread, sizeof set, &set) == 0;
}

}  // namespace

double CpuSpeeds::attainable() const {
  double s = 0.0;
  for (double v : together) s += v;
  return s;
}

int CpuSpeeds::fastest() const {
  if (!valid()) return -1;
  return cpus[static_cast<std::size_t>(std::max_element(alone.begin(), alone.end()) -
                                       alone.begin())];
}

PinCurrentThread::PinCurrentThread(int cpu) {
  CPU_ZERO(&old_);
  if (cpu < 0 || pthread_getaffinity_np(pthread_self(), sizeof old_, &old_) != 0) return;
  pinned_ = pin(pthread_self(), cpu);
}

PinCurrentThread::~PinCurrentThread() {
  if (pinned_) pthread_setaffinity_np(pthread_self(), sizeof old_, &old_);
}

std::string CpuSpeeds::describe() const {
  if (!valid()) return "not measured";
  std::string out;
  char buf[64];
  for (std::size_t i = 0; i < cpus.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%scpu%d %.2f", i ? ", " : "", cpus[i], together[i]);
    out += buf;
  }
  out += " (together; alone";
  for (std::size_t i = 0; i < cpus.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s %.2f", i ? "," : "", alone[i]);
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "; fastest %.3g multiply-adds/s)", fastest_rate);
  return out + buf;
}

CpuSpeeds measure_cpu_speeds(double seconds) {
  CpuSpeeds s;
  cpu_set_t mask;
  CPU_ZERO(&mask);
  if (sched_getaffinity(0, sizeof mask, &mask) != 0) return s;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &mask)) s.cpus.push_back(c);
  const std::size_t n = s.cpus.size();
  // A thread is pinned before it starts its loop: it waits on `start` until all n are pinned.
  const auto run = [&](const std::vector<std::size_t>& which, std::vector<double>& rates) {
    std::atomic<int> start{0};
    std::vector<std::thread> threads;
    bool ok = true;
    for (std::size_t i : which) {
      threads.emplace_back([&, i] {
        rates[i] = arithmetic_rate(seconds, start, 1 + static_cast<int>(which.size()));
      });
      ok = pin(threads.back().native_handle(), s.cpus[i]) && ok;
    }
    start.fetch_add(1);  // the last starter: every thread has been pinned
    for (auto& t : threads) t.join();
    return ok;
  };
  std::vector<double> alone(n, 0.0), together(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    if (!run({i}, alone)) return {};
  std::vector<std::size_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = i;
  if (!run(all, together)) return {};
  const double fastest = *std::max_element(alone.begin(), alone.end());
  for (std::size_t i = 0; i < n; ++i) {
    alone[i] /= fastest;
    together[i] /= fastest;
  }
  s.fastest_rate = fastest * 100000.0 * 8.0;  // chunks/s x multiply-adds per chunk
  s.alone = std::move(alone);
  s.together = std::move(together);
  return s;
}

}  // namespace stiffbench::bench

// How fast each CPU this process may use runs a fixed arithmetic loop, alone and with all of
// them busy at once. On a virtual machine the vCPUs need not be equal: on the project's 2-vCPU
// machine one of them (either) at times runs the same loop at 0.6-0.7x the other's rate, and then
// no code reaches a 2-thread speed-up above 1.7. The summary
// prints the probe taken before and after the benchmarks; the right-hand-side benchmarks probe
// just before their timing loop (bench_rhs.cpp, time_on_fastest_cpu) and the summary sets each
// 2-thread speed-up beside what that probe allowed.
#pragma once

#include <sched.h>

#include <string>
#include <vector>

namespace stiffbench::bench {

struct CpuSpeeds {
  std::vector<int> cpus;  // the CPUs of this process's affinity mask
  // Loop iterations per second of each CPU, divided by the fastest CPU's rate when alone.
  std::vector<double> alone;     // each pinned thread running by itself
  std::vector<double> together;  // all pinned threads at once
  double fastest_rate = 0.0;     // multiply-adds per second of the fastest CPU alone
  bool valid() const { return !cpus.empty() && alone.size() == cpus.size(); }
  // The speed-up that work divided perfectly among all the CPUs would reach over one thread on
  // the fastest CPU: sum(together) (alone's fastest rate is 1 by construction).
  double attainable() const;
  // "cpu0 1.00, cpu1 0.69 (together; alone 1.00, 0.72; fastest 2.1e9 multiply-adds/s)".
  std::string describe() const;
  // The CPU with the highest `alone` rate (-1 when not measured).
  int fastest() const;
};

// Runs the loop for about `seconds` on each CPU alone, then on all at once (threads pinned with
// pthread_setaffinity_np). Empty when the affinity mask cannot be read or set.
CpuSpeeds measure_cpu_speeds(double seconds = 0.1);

// Pins the calling thread to one CPU while it lives and restores its previous affinity mask
// after. For 1-thread timing loops only: threads created meanwhile (an OpenMP pool growing)
// would inherit the one-CPU mask.
class PinCurrentThread {
 public:
  explicit PinCurrentThread(int cpu);
  ~PinCurrentThread();
  PinCurrentThread(const PinCurrentThread&) = delete;
  PinCurrentThread& operator=(const PinCurrentThread&) = delete;
  bool pinned() const { return pinned_; }

 private:
  cpu_set_t old_;
  bool pinned_ = false;
};

}  // namespace stiffbench::bench

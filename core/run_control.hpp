// Stopping a run from outside: a wall-clock limit per row (`--max-wall S`) and an
// interrupt request (SIGINT/SIGTERM in the command line).
//
// Both are polled at every f evaluation (OdeSystem counts evaluations at the system boundary,
// so every integrator, library references included, passes there) and once per step by the
// driver (for methods that make no f evaluations: xpbd, projective_dynamics, stable_fluids). The
// poll costs one relaxed atomic load while no row clock with a limit and no interrupt is active.
//
// - A row over its limit: the poll throws WallLimitExceeded; the driver ends that run with
//   Status::timeout and a message naming the limit and the time reached, and the study goes on
//   with its next row. The clock of a row starts with the outermost RowClock on the thread: the
//   driver opens one per run, and an experiment whose row is several runs (a stability
//   bisection, the repeats of a work-precision setting) opens one around the whole row, which
//   the driver's runs then share.
// - An interrupt: the poll throws Interrupted, which deliberately does not derive from
//   std::exception, so the handlers that end one row with status error let it through; it
//   unwinds to the caller (the command line removes temporaries and exits 128 + signal: 130 for
//   SIGINT, 143 for SIGTERM). Library callbacks (SUNDIALS, GSL) catch it at the C boundary and
//   the driver rethrows it when the library returns.
#pragma once

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>

namespace stiffbench {

// The wall-clock limit of one row in seconds; 0 (the default) means none. Process-wide: the
// command line sets it from --max-wall; a program linking the library may set it too.
void set_wall_limit(double seconds);
double wall_limit();

// Thrown by the poll when the current row's clock passed its limit.
class WallLimitExceeded : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Thrown by the poll after request_interrupt(): not a std::exception (see above).
struct Interrupted {
  int signal = 0;
};

// Requests that the runs stop at their next poll. Async-signal-safe (a lock-free atomic store):
// the command line's SIGINT/SIGTERM handler calls it.
void request_interrupt(int signal) noexcept;
// The signal of a pending request, 0 when none.
int interrupt_requested() noexcept;
// Forgets a pending request (tests; a program that handled the interruption).
void clear_interrupt() noexcept;

// The clock of one row on this thread. The outermost RowClock starts the clock with the given
// limit (0: none); nested ones share it. Not copyable; destroyed in reverse order.
class RowClock {
 public:
  explicit RowClock(double limit_s = wall_limit());
  ~RowClock();
  RowClock(const RowClock&) = delete;
  RowClock& operator=(const RowClock&) = delete;

  // True when this thread's row has a limit and has passed it (checked now, not at a poll).
  static bool expired();

 private:
  bool outermost_ = false;
};

namespace detail {
// Non-zero while an interrupt is pending or some thread's row has a limit.
extern std::atomic<int> g_poll;
void poll_slow();
}  // namespace detail

// Throws Interrupted or WallLimitExceeded when the run must stop; otherwise returns at once.
inline void poll_run_control() {
  if (detail::g_poll.load(std::memory_order_relaxed) != 0) detail::poll_slow();
}

}  // namespace stiffbench

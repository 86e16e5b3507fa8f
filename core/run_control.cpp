#include "core/run_control.hpp"

#include <cmath>
#include <sstream>

#include "core/types.hpp"

namespace stiffbench {

namespace detail {
std::atomic<int> g_poll{0};
}  // namespace detail

namespace {

using Clock = std::chrono::steady_clock;

std::atomic<double> g_wall_limit{0.0};
std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need a lock-free atomic");

// The row open on this thread. The clock is read at every `every`-th poll; `every` adapts so
// that reads are about 1–10 ms apart whatever an f evaluation costs (a 2-component test problem
// evaluates f in nanoseconds, an SPH scene in milliseconds), keeping the poll's cost negligible
// and the overshoot of the limit small.
struct RowState {
  int depth = 0;
  double limit = 0.0;
  Clock::time_point start, last_read;
  long count = 0, every = 1;
};
thread_local RowState t_row;

double elapsed(const Clock::time_point& since, const Clock::time_point& now) {
  return std::chrono::duration<double>(now - since).count();
}

[[noreturn]] void throw_limit(double limit, double seconds) {
  std::ostringstream msg;
  msg << "wall-clock limit of " << limit << " s exceeded after " << seconds << " s (--max-wall)";
  throw WallLimitExceeded(msg.str());
}

}  // namespace

void set_wall_limit(double seconds) {
  require_input(std::isfinite(seconds) && seconds >= 0,
                "--max-wall must be a finite number of seconds >= 0 (0: no limit)");
  g_wall_limit.store(seconds);
}

double wall_limit() { return g_wall_limit.load(); }

void request_interrupt(int signal) noexcept {
  if (g_signal.exchange(signal == 0 ? -1 : signal) == 0) detail::g_poll.fetch_add(1);
}

int interrupt_requested() noexcept { return g_signal.load(std::memory_order_relaxed); }

void clear_interrupt() noexcept {
  if (g_signal.exchange(0) != 0) detail::g_poll.fetch_sub(1);
}

RowClock::RowClock(double limit_s) {
  if (t_row.depth++ > 0) return;  // nested: the row's clock is already running
  outermost_ = true;
  t_row.limit = limit_s > 0 && std::isfinite(limit_s) ? limit_s : 0.0;
  t_row.start = t_row.last_read = Clock::now();
  t_row.count = 0;
  t_row.every = 1;
  if (t_row.limit > 0) detail::g_poll.fetch_add(1);
}

RowClock::~RowClock() {
  --t_row.depth;
  if (!outermost_) return;
  if (t_row.limit > 0) detail::g_poll.fetch_sub(1);
  t_row.limit = 0.0;
}

bool RowClock::expired() {
  return t_row.depth > 0 && t_row.limit > 0 && elapsed(t_row.start, Clock::now()) > t_row.limit;
}

void detail::poll_slow() {
  if (const int s = g_signal.load(std::memory_order_relaxed)) throw Interrupted{s};
  RowState& r = t_row;
  if (r.depth == 0 || r.limit <= 0 || ++r.count < r.every) return;
  r.count = 0;
  const Clock::time_point now = Clock::now();
  const double since = elapsed(r.last_read, now);
  r.last_read = now;
  if (since < 1e-3 && r.every < (1L << 20))
    r.every *= 2;
  else if (since > 1e-2 && r.every > 1)
    r.every /= 2;
  const double used = elapsed(r.start, now);
  if (used > r.limit) throw_limit(r.limit, used);
}

}  // namespace stiffbench

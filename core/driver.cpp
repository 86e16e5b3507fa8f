#include "core/driver.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace stiffbench {

namespace {

// The evaluations counted at the system boundary since `before`, added to the run's statistics.
void count_evaluations(const OdeSystem& sys, const EvalCounters& before, SolveStats& stats) {
  const EvalCounters& now = sys.counters();
  stats.f_evals += now.f_evals - before.f_evals;
  stats.jac_evals += now.jac_evals - before.jac_evals;
  stats.fe_evals += now.fe_evals - before.fe_evals;
  stats.fi_evals += now.fi_evals - before.fi_evals;
}

// ‖y‖∞ with NaN propagated (any NaN entry makes the result NaN), over OpenMP threads for large
// states (max is order-independent: the same result for any thread count).
double max_norm(CVecRef y) {
  const Index n = y.size();
  const double* p = y.data();
  double m = 0.0;
  bool nan = false;
  if (n >= 100000) {
#pragma omp parallel for schedule(static) reduction(max : m) reduction(|| : nan)
    for (Index i = 0; i < n; ++i) {
      const double a = std::abs(p[i]);
      nan = nan || std::isnan(a);
      m = a > m ? a : m;
    }
  } else {
    for (Index i = 0; i < n; ++i) {
      const double a = std::abs(p[i]);
      nan = nan || std::isnan(a);
      m = a > m ? a : m;
    }
  }
  return nan ? std::numeric_limits<double>::quiet_NaN() : m;
}

// dst = src (resized), over OpenMP threads for large states.
void copy_state(CVecRef src, Vec& dst) {
  const Index n = src.size();
  if (n < 100000) {
    dst = src;
    return;
  }
  dst.resize(n);
  const double* from = src.data();
  double* to = dst.data();
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) to[i] = from[i];
}

std::atomic<long> g_faults{0};
thread_local bool t_timeouts_expected = false;

// A model or integrator that threw mid-run: the run ends here with status error and the
// exception's message; the study goes on with its other rows.
void record_fault(RunResult& r, const std::exception& e, double t_goal) {
  r.stats.status = Status::error;
  std::ostringstream msg;
  msg.precision(12);  // t and t + h apart even for tiny steps
  msg << "exception in the step from t = " << r.t << " towards " << t_goal << ": " << e.what();
  r.stats.message = msg.str();
  ++g_faults;
}

// The row's wall-clock limit passed during the run: status timeout; counted like a fault, since
// the row has no result.
void record_timeout(RunResult& r, const std::string& what, double t_goal) {
  r.stats.status = Status::timeout;
  std::ostringstream msg;
  msg.precision(12);
  msg << what << ", in the step from t = " << r.t << " towards " << t_goal;
  r.stats.message = msg.str();
  if (!t_timeouts_expected) ++g_faults;
}

// The admissible-set check at an output time: the first component of `nonneg` (the model's
// non-negative components) below -bound ends the run with status invalid_state and a message
// naming the component, its value, t and the bound. Returns true when it did.
bool left_admissible_set(const OdeSystem& sys, const std::vector<Index>& nonneg, double bound,
                         RunResult& r) {
  for (const Index i : nonneg) {
    if (!(r.y[i] < -bound)) continue;
    r.stats.status = Status::invalid_state;
    std::ostringstream msg;
    msg.precision(12);
    msg << "component y[" << i << "]";
    if (const std::string name = sys.component_name(i); !name.empty()) msg << " (" << name << ")";
    msg << " = " << r.y[i] << " < -" << bound << " at t = " << r.t
        << ": the model's solution keeps it non-negative";
    r.stats.message = msg.str();
    return true;
  }
  return false;
}

// The bound of that check when the run has no absolute tolerance: round-off relative to the
// state's size (core/driver.hpp).
double roundoff_bound(CVecRef y) { return 1e-8 * std::max(1.0, max_norm(y)); }

}  // namespace

long fault_count() { return g_faults.load(); }

void count_row_timeout() {
  if (!t_timeouts_expected) ++g_faults;
}

ExpectedTimeouts::ExpectedTimeouts() : previous_(t_timeouts_expected) {
  t_timeouts_expected = true;
}
ExpectedTimeouts::~ExpectedTimeouts() { t_timeouts_expected = previous_; }

long fixed_step_count(double t0, double t_end, double h, long max_steps) {
  require_input(std::isfinite(h) && h > 0,
                "step size h must be > 0 (got " + std::to_string(h) + ")");
  require_input(std::isfinite(t_end) && t_end > t0, "t-end must be > the model's initial time " +
                                                        std::to_string(t0) + " (got " +
                                                        std::to_string(t_end) + ")");
  const double n = std::max(1.0, std::round((t_end - t0) / h));
  if (n > static_cast<double>(max_steps)) {
    std::ostringstream msg;
    msg << "h = " << h << " over [" << t0 << ", " << t_end << "] would take " << n
        << " steps (limit " << max_steps << ")";
    throw BadInput(msg.str());
  }
  return static_cast<long>(n);
}

namespace {

// A system of a program's own may say anything: a run needs at least one unknown and an initial
// state of the system's dimension (a mismatch would read or write past the integrator's vectors).
void check_state_size(const OdeSystem& sys, Index y0_size) {
  require_input(sys.dimension() > 0, "system '" + sys.name() + "': dimension " +
                                         std::to_string(sys.dimension()) +
                                         ": a system needs at least one unknown");
  require_input(y0_size == sys.dimension(),
                "system '" + sys.name() + "': the initial state has " + std::to_string(y0_size) +
                    " entries, the dimension is " + std::to_string(sys.dimension()));
}

}  // namespace

RunResult run_fixed_step(const OdeSystem& sys, Integrator& integ, const FixedStepOptions& opt,
                         const Observer& observer) {
  const Vec y0 = sys.initial_state();
  return run_fixed_step_from(sys, integ, sys.initial_time(), y0, opt, observer);
}

RunResult run_fixed_step_from(const OdeSystem& sys, Integrator& integ, double t0, CVecRef y0,
                              const FixedStepOptions& opt, const Observer& observer) {
  const long n = fixed_step_count(t0, opt.t_end, opt.h, opt.max_steps);
  check_state_size(sys, y0.size());
  check_compatible(integ.info(), sys);

  RunResult r;
  r.n_steps = n;
  r.h = (opt.t_end - t0) / static_cast<double>(n);
  // The copy and ‖y0‖∞ over OpenMP threads for large states (a cloth 512² state is 12.6 MB).
  // With this and the benchmark's untimed first run, a 20-step symplectic_euler run's steps take
  // 0.15-0.22 ms more each than direct step() calls (2 threads; bench/bench_steps.cpp, the
  // solve/ and step/ rows of scripts/bench.sh).
  copy_state(y0, r.y);
  r.t = t0;
  const double bound = opt.blowup_factor * std::max(1.0, max_norm(y0));

  // Output at steps round(j·N/outputs), j = 0..outputs.
  const long outputs = opt.outputs <= 0 ? 1 : std::min(opt.outputs, n);
  long next_output_index = 1;
  auto output_step = [&](long j) {
    return static_cast<long>(std::llround(static_cast<double>(j) * static_cast<double>(n) /
                                          static_cast<double>(outputs)));
  };

  const EvalCounters before = sys.counters();
  const std::vector<Index> nonneg = sys.nonnegative_components();
  const RowClock clock;
  const auto start = std::chrono::steady_clock::now();
  integ.reset(sys, t0, r.y);
  if (observer) observer(r.t, r.y);
  for (long k = 0; k < n; ++k) {
    Status s = Status::ok;
    try {
      poll_run_control();  // methods without f evaluations (xpbd) are stopped here
      s = integ.step(sys, r.t, r.y, r.h, r.stats);
    } catch (const BadInput&) {
      throw;  // a setting refused lazily is still bad input
    } catch (const WallLimitExceeded& e) {
      record_timeout(r, e.what(), r.t + r.h);
      break;
    } catch (const std::exception& e) {
      record_fault(r, e, r.t + r.h);
      break;
    }
    r.t = (k + 1 == n) ? opt.t_end : t0 + static_cast<double>(k + 1) * r.h;
    ++r.stats.steps;
    // Methods that enforce the constraints themselves (rattle) are not projected afterwards.
    const bool projected =
        s == Status::ok && sys.has_constraints() && !integ.info().requires_.constraints;
    if (projected) sys.project(r.t, r.y);
    if (s != Status::ok) {
      r.stats.status = s;
      if (r.stats.message.empty())
        r.stats.message = to_string(s) + " in the step ending at t = " + std::to_string(r.t);
      break;
    }
    // NaN propagates to a failed comparison. The method's own ‖y‖∞ when it has one (computed
    // while it wrote y) and the projection did not move y since.
    const std::optional<double> known = projected ? std::nullopt : integ.last_step_max_norm();
    const double norm = known ? *known : max_norm(r.y);
    if (!(norm <= bound)) {
      r.stats.status = Status::unstable;
      std::ostringstream msg;
      msg << "blow-up at t = " << r.t << " (step " << k + 1 << "): ‖y‖∞ = " << norm << " exceeds "
          << bound;
      r.stats.message = msg.str();
      break;
    }
    if (k + 1 == output_step(next_output_index)) {
      if (!nonneg.empty() && left_admissible_set(sys, nonneg, roundoff_bound(r.y), r)) break;
      if (observer) observer(r.t, r.y);
      ++next_output_index;
    }
  }
  r.stats.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  count_evaluations(sys, before, r.stats);
  return r;
}

RunResult run_adaptive(const OdeSystem& sys, Integrator& integ, const AdaptiveOptions& opt,
                       const Observer& observer) {
  const double t0 = sys.initial_time();
  require_input(std::isfinite(opt.t_end) && opt.t_end > t0,
                "t-end must be > the model's initial time " + std::to_string(t0));
  require_input(integ.supports_adaptive(),
                "integrator '" + integ.info().name + "' is fixed-step only: give --h");
  check_compatible(integ.info(), sys);
  RunResult r;
  r.y = sys.initial_state();
  check_state_size(sys, r.y.size());
  r.t = t0;
  // The output stops: opt.times (then t_end), or `outputs` equal intervals computed one at a time,
  // so a large --outputs costs no memory.
  std::vector<double> stops = opt.times;
  long n_stops = 0;
  if (stops.empty()) {
    n_stops = std::max(1L, opt.outputs);
  } else {
    double prev = t0;
    for (const double t : stops) {
      require_input(std::isfinite(t) && t > prev && t <= opt.t_end,
                    "output times must be finite, increasing, after the initial time " +
                        std::to_string(t0) + " and not after t-end " + std::to_string(opt.t_end));
      prev = t;
    }
    if (stops.back() < opt.t_end) stops.push_back(opt.t_end);
    n_stops = static_cast<long>(stops.size());
  }
  const auto stop_at = [&](long j) {  // j = 1, ..., n_stops
    if (!stops.empty()) return stops[static_cast<std::size_t>(j - 1)];
    return j == n_stops
               ? opt.t_end
               : t0 + (opt.t_end - t0) * static_cast<double>(j) / static_cast<double>(n_stops);
  };
  const std::vector<Index> nonneg = sys.nonnegative_components();
  const std::optional<double> atol = integ.absolute_tolerance();
  const EvalCounters before = sys.counters();
  const RowClock clock;
  const auto start = std::chrono::steady_clock::now();
  integ.reset(sys, t0, r.y);
  if (observer) observer(r.t, r.y);
  for (long j = 1; j <= n_stops; ++j) {
    const double t_out = stop_at(j);
    Status s = Status::ok;
    try {
      poll_run_control();
      s = integ.advance_to(sys, t_out, r.y, r.stats);
    } catch (const BadInput&) {
      throw;
    } catch (const WallLimitExceeded& e) {
      record_timeout(r, e.what(), t_out);
      break;
    } catch (const std::exception& e) {
      record_fault(r, e, t_out);
      break;
    }
    if (s != Status::ok) {
      r.stats.status = s;
      break;
    }
    r.t = t_out;
    if (!r.y.allFinite()) {
      r.stats.status = Status::unstable;
      r.stats.message = "non-finite state at t = " + std::to_string(t_out);
      break;
    }
    if (!nonneg.empty() &&
        left_admissible_set(sys, nonneg, atol && *atol > 0 ? *atol : roundoff_bound(r.y), r))
      break;
    if (observer) observer(r.t, r.y);
  }
  r.stats.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.stats.f_evals = 0;  // the system's count replaces what advance_to() may have set
  count_evaluations(sys, before, r.stats);
  r.n_steps = r.stats.steps;
  return r;
}

}  // namespace stiffbench

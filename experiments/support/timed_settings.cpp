#include "experiments/support/timed_settings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <ostream>

#include "core/run_control.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

namespace {

// The first field in which a repeat differs from the first run ("" when none): the status, the
// final state (bit for bit) and every SolveStats field but the wall time.
std::string repeat_mismatch(const RunResult& a, const RunResult& b) {
  if (a.stats.status != b.stats.status)
    return "status (" + to_string(b.stats.status) + " against " + to_string(a.stats.status) + ")";
  if (a.y.size() != b.y.size() || a.y != b.y)
    return "the final state (max difference " +
           (a.y.size() == b.y.size() ? format_short(max_abs_diff(a.y, b.y)) : "size") + ")";
  const auto names = SolveStats::field_names();
  const auto va = a.stats.field_values(), vb = b.stats.field_values();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] != "wall_s" && va[i] != vb[i])
      return names[i] + " (" + vb[i] + " against " + va[i] + ")";
  if (a.stats.library_f_evals != b.stats.library_f_evals)
    return "library_f_evals (" + std::to_string(b.stats.library_f_evals) + " against " +
           std::to_string(a.stats.library_f_evals) + ")";
  return {};
}

double mescd(CVecRef y, CVecRef ref, double ratio) {
  double m = 0;
  for (Index i = 0; i < y.size(); ++i)
    m = std::max(m, std::abs(y[i] - ref[i]) / (ratio + std::abs(ref[i])));
  return -std::log10(m);
}

// One run of a point: an adaptive method at its tolerance, a fixed-step method at its step.
RunResult run_point(const TimedSweep& c, const WorkPrecisionPoint& p) {
  const std::string& name = c.integrators[p.integ];
  if (p.adaptive) {
    Params prm = c.params;
    prm.set("rtol", format_full(c.tols[p.k]));
    prm.set("atol", format_full(c.tols[p.k] * c.atol_factor));
    auto integ = c.in.create_integrator(name, prm);
    return run_adaptive(c.sys, *integ, {c.t_end, 0});
  }
  FixedStepOptions opt;
  opt.t_end = c.t_end;
  opt.h = c.hs[p.k];
  return run_fixed_step(c.sys, *c.instances[p.integ], opt);
}

// Whether a point runs again in a later round (see kRepeatBudget in the header).
bool repeats_more(const TimedSweep& c, const WorkPrecisionPoint& p) {
  double total = 0;
  for (double w : p.walls) total += w;
  return !p.stopped && static_cast<int>(p.walls.size()) < c.max_runs &&
         p.walls.front() < kRepeatLongRun && total < kRepeatBudget;
}

// Records a point's first run and reports it as run `done` of `total`.
void record_first_run(const TimedSweep& c, WorkPrecisionPoint& p, RunResult r, std::size_t done,
                      std::size_t total) {
  p.walls.push_back(r.stats.wall_s);
  p.stopped = r.stats.status != Status::ok;  // a failed run is not repeated
  p.first = std::move(r);
  if (c.progress) {
    const RunResult& f = p.first;
    const bool ok = f.stats.status == Status::ok;
    *c.progress << "[" << done << "/" << total << "] " << c.integrators[p.integ] << " "
                << (p.adaptive ? "rtol=" + format_short(c.tols[p.k], 0) : "h=" + format_full(f.h))
                << " error="
                << (ok ? format_short(max_abs_diff(f.y, c.ref)) : to_string(f.stats.status))
                << " f_evals=" << f.stats.f_evals << " (" << format_short(f.stats.wall_s, 2)
                << " s)\n"
                << std::flush;
  }
}

// Records a repeat: its wall time, or a stop on a timeout or on a result differing from run 1.
void record_repeat(WorkPrecisionPoint& p, const RunResult& r) {
  if (r.stats.status == Status::timeout) {
    p.stopped = true;  // over --max-wall: the runs so far stand
    return;
  }
  p.mismatch = repeat_mismatch(p.first, r);
  if (!p.mismatch.empty()) {
    p.mismatch = "not deterministic: run " + std::to_string(p.walls.size() + 1) +
                 " differs from run 1 in " + p.mismatch;
    p.stopped = true;
  } else {
    p.walls.push_back(r.stats.wall_s);
  }
}

}  // namespace

// The points in the rows' order: per integrator, its tolerance ladder or its step ladder.
std::vector<WorkPrecisionPoint> work_precision_points(const TimedSweep& c) {
  std::vector<WorkPrecisionPoint> points;
  for (std::size_t i = 0; i < c.instances.size(); ++i) {
    const bool adaptive = c.instances[i]->supports_adaptive();
    for (std::size_t k = 0; k < (adaptive ? c.tols.size() : c.hs.size()); ++k)
      points.push_back(WorkPrecisionPoint{i, k, adaptive, {}, {}, false, {}});
  }
  return points;
}

// Runs the points in rounds, each shuffled with the seed, until no point repeats any more.
void run_rounds(const TimedSweep& c, std::vector<WorkPrecisionPoint>& points) {
  std::size_t done = 0;
  for (int round = 1; round <= c.max_runs; ++round) {
    std::size_t ran = 0;
    double spent = 0;
    for (const std::size_t idx : run_order(points.size(), c.seed, round)) {
      WorkPrecisionPoint& p = points[idx];
      if (round > 1 && !repeats_more(c, p)) continue;
      RunResult r = run_point(c, p);
      ++ran;
      spent += r.stats.wall_s;
      if (round == 1)
        record_first_run(c, p, std::move(r), ++done, points.size());
      else
        record_repeat(p, r);
    }
    if (c.progress && round > 1 && ran > 0)
      *c.progress << "repeat round " << round << "/" << c.max_runs << ": " << ran << " runs ("
                  << format_short(spent, 2) << " s)\n"
                  << std::flush;
    if (ran == 0) break;
  }
}

// The row of point `idx`: its first run's counters, the timing spread, the errors.
WorkPrecisionRow work_precision_row(const TimedSweep& c, const WorkPrecisionPoint& p,
                                    std::size_t idx) {
  WorkPrecisionRow row;
  row.model = c.model;
  row.integrator = c.integrators[p.integ];
  row.setting = p.adaptive ? "rtol=" + format_short(c.tols[p.k], 0) : "h=" + format_full(p.first.h);
  row.stats = p.first.stats;
  row.wall = timing_spread(p.walls, c.seed, idx);
  row.stats.wall_s = row.wall.median;
  if (!p.mismatch.empty()) {
    row.stats.status = Status::error;
    row.stats.message = p.mismatch;
  }
  const bool ok = row.stats.status == Status::ok;
  row.error = ok ? max_abs_diff(p.first.y, c.ref) : std::numeric_limits<double>::quiet_NaN();
  row.mescd =
      ok ? mescd(p.first.y, c.ref, c.atol_factor) : std::numeric_limits<double>::quiet_NaN();
  return row;
}

WorkPrecisionRow run_work_precision_setting(const StudyInputs& in, const OdeSystem& sys,
                                            const std::string& model, const std::string& integrator,
                                            const Params& params, bool adaptive, double setting,
                                            double atol_factor, double t_end, const Vec& ref,
                                            int repeats, unsigned long seed, std::size_t stream,
                                            double wall_limit_s) {
  const std::unique_ptr<Integrator> instance = in.create_integrator(integrator, params);
  const TimedSweep c{in,    sys,         model,   params, {integrator}, {instance.get()},
                     t_end, atol_factor, repeats, seed,   {setting},    {setting},
                     ref,   nullptr};
  std::vector<WorkPrecisionPoint> points = {WorkPrecisionPoint{0, 0, adaptive, {}, {}, false, {}}};
  const double global = wall_limit();
  const double limit =
      global > 0 && (wall_limit_s <= 0 || global < wall_limit_s) ? global : wall_limit_s;
  const RowClock clock(limit);
  run_rounds(c, points);
  return work_precision_row(c, points.front(), stream);
}

}  // namespace stiffbench

// Timed runs of integrator settings (an adaptive method at a tolerance, a fixed-step method at a
// step), as work-precision times its points and recommend its candidates: every point runs in
// rounds shuffled with the seed, repeats within the limits of experiments/support/timing.hpp and
// checked for determinism, each measured against a reference state (error, mescd).
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "experiments/framework/resolve.hpp"
#include "experiments/support/timing.hpp"

namespace stiffbench {

struct WorkPrecisionRow {
  std::string model, integrator, setting;
  double error = 0, mescd = 0;
  SolveStats stats;  // the first run's (wall_s: the median over the repeats)
  TimingSpread wall;
  // ok, and error <= kFloorFactor × the reference's estimated error (see "The reference").
  bool at_reference_floor = false;
};

// One row's point: its integrator and ladder index, its first run and the wall times so far.
struct WorkPrecisionPoint {
  std::size_t integ, k;
  bool adaptive;
  RunResult first;
  std::vector<double> walls;
  bool stopped = false;
  std::string mismatch;
};

// What every point of one sweep shares: the inputs (adaptive points create their integrator
// from `in` by label with rtol/atol added to `params`), the model, the integrators (fixed-step
// points reuse `instances`), the ladders and the reference.
struct TimedSweep {
  const StudyInputs& in;
  const OdeSystem& sys;
  std::string model;
  Params params;
  std::vector<std::string> integrators;  // labels, in the order of `instances`
  std::vector<Integrator*> instances;
  double t_end = 0, atol_factor = 0;
  int max_runs = 1;  // the most runs per point (a study's repeats)
  unsigned long seed = 1;
  std::vector<double> tols, hs;
  const Vec& ref;
  std::ostream* progress = nullptr;
};

// The points in the rows' order: per integrator, its tolerance ladder or its step ladder.
std::vector<WorkPrecisionPoint> work_precision_points(const TimedSweep& c);
// Runs the points in rounds, each shuffled with the seed, until no point repeats any more.
void run_rounds(const TimedSweep& c, std::vector<WorkPrecisionPoint>& points);
// The row of point `idx`: its first run's counters, the timing spread, the errors.
WorkPrecisionRow work_precision_row(const TimedSweep& c, const WorkPrecisionPoint& p,
                                    std::size_t idx);

// One setting of the sweep (recommend): `integrator` (a label of `in`, created with `params`)
// at tolerance `setting` (adaptive: rtol = setting, atol = atol_factor·setting) or at step
// `setting` (fixed step) over [t0, t_end], timed like a work-precision point (repeats up to
// `repeats` under kRepeatLongRun and kRepeatBudget, repeats checked for determinism) and
// measured against `ref` (error, mescd). All runs of the setting share one row clock of
// `wall_limit_s` seconds (0: none), or the --max-wall limit when that is smaller, so a slow
// setting ends as `timeout`.
WorkPrecisionRow run_work_precision_setting(const StudyInputs& in, const OdeSystem& sys,
                                            const std::string& model, const std::string& integrator,
                                            const Params& params, bool adaptive, double setting,
                                            double atol_factor, double t_end, const Vec& ref,
                                            int repeats, unsigned long seed, std::size_t stream,
                                            double wall_limit_s);

}  // namespace stiffbench

// `stiffbench solve`: one run of a model with an integrator (experiments/commands/solve.cpp).
// Included by experiments/commands/list_describe.hpp with the other subcommands.
#pragma once

#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "core/types.hpp"

namespace stiffbench {

struct SolveOptions {
  std::string model, integrator;
  Params params;
  // NaN: not given (adaptive mode / the model's default end time).
  double h = std::numeric_limits<double>::quiet_NaN();
  double t_end = std::numeric_limits<double>::quiet_NaN();
  long outputs = 100;
  std::string out_csv;  // empty: no trajectory file; with frames > 0, the output directory
  long frames = 0;      // > 0: write frames + observables.csv into the directory out_csv
  std::string frame_format = "vtu";  // vtu (+ frames.pvd) or vtk (legacy)
  // Output times instead of `outputs` equal intervals (--times; exclusive with log_outputs and
  // frames). They must be finite, strictly increasing and in (t0, t_end]; without --t-end the
  // run ends at the last of them. Adaptive integrators stop exactly at each (no
  // interpolation); a fixed-step run reports the state at the step nearest to each (ties to the
  // later step), whose actual t is printed and written. The trajectory CSV then holds exactly
  // one row per requested time (t, y0, y1, ...; t0 is not included).
  std::vector<double> times;
  // --log-outputs N: N output times from log_output_times(t0, t_end, N, log_first).
  long log_outputs = 0;
  double log_first = std::numeric_limits<double>::quiet_NaN();  // --log-first (NaN: default)
};
// The spec `solve --frames N --out DIR` records in DIR/solve.json (model, params, integrator, h
// and t_end as given (null: not given), frames, frame_format) and compares with
// check_existing_results before it runs; `--out FILE.csv` records none, so an existing FILE is
// refused unless force_output().
nlohmann::json solve_spec(const SolveOptions& opt);
void cmd_solve(const SolveOptions& opt, std::ostream& out, std::ostream& err);

// An upper bound of the size in bytes of a trajectory CSV of `rows` states of `dimension`
// components (the header, then t and the state per row in the shortest round-trip form). solve
// checks it against the free space of --out's file system before the run, and notes a file of
// kLargeTrajectoryBytes or more on the error stream (40 steps of cloth 512² at the default
// --outputs: 41 rows of 1,572,865 numbers, up to 1.5 GiB).
double trajectory_bytes_bound(long rows, Index dimension);
inline constexpr double kLargeTrajectoryBytes = 256.0 * 1024 * 1024;

// "t1,t2,..." of --times as numbers (BadInput naming --times for an empty or non-numeric item).
std::vector<double> parse_times(const std::string& list);

// The N times of --log-outputs, geometrically spaced in t - t0 from `first` to t_end:
//   t_k = t0 + (first - t0) · ((t_end - t0)/(first - t0))^((k-1)/(N-1)),  k = 1..N,
// with t_N = t_end exactly. Default first (NaN): t0 + (t_end - t0)·10^-(N-1), i.e. one output
// per decade ending at t_end (N = 12 on Robertson's [0, 1e11]: 1, 10, ..., 1e11). N = 1 gives
// {t_end}. BadInput naming --log-outputs / --log-first for N < 1, a first time outside
// (t0, t_end) or one given with N = 1, or spacing too fine to stay increasing.
std::vector<double> log_output_times(double t0, double t_end, long n,
                                     double first = std::numeric_limits<double>::quiet_NaN());

}  // namespace stiffbench

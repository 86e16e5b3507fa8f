// `stiffbench solve` (experiments/commands/solve.hpp): one run of a model with an integrator, its
// summary on `out`, and optionally its trajectory (--out FILE.csv) or frames (--frames N --out
// DIR). cmd_solve resolves the run (end time, step, output times), checks the output, runs it and
// prints the summary, each step a helper below.
#include "experiments/commands/solve.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <system_error>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/resolve.hpp"
#include "experiments/output/frames.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"

namespace stiffbench {

namespace {

// How the run steps: adaptive (the integrator's own step control), or fixed step h as given
// (--h) or the model's suggested step (its CFL limit).
struct StepChoice {
  double h = std::numeric_limits<double>::quiet_NaN();
  bool adaptive = false;
  std::optional<SuggestedStep> suggested;
};

// One requested output time (--times / --log-outputs) and the state recorded for it.
struct TimedRow {
  double requested, t;
  Vec y;
};

// The run as cmd_solve resolves it, shared by its helpers.
struct SolveRun {
  SolveRun(const SolveOptions& o, const OdeSystem& s, Integrator& i) : opt(o), sys(s), integ(i) {}

  const SolveOptions& opt;
  const OdeSystem& sys;
  Integrator& integ;
  bool timed = false;      // --times or --log-outputs
  std::string times_flag;  // which of them, for messages
  bool frames = false;     // --frames N > 0
  double t0 = 0.0, t_end = 0.0;
  StepChoice step;
  std::vector<double> times;  // the requested output times
  FixedStepOptions fo;
  long n_steps = 0;  // fixed step only
  // Trajectory CSV: the --out file, or DIR/trajectory.csv with --frames for models without
  // particles (particle models write VTK frames instead); empty: none.
  std::unique_ptr<FrameWriter> frame_writer;
  std::string traj_path;
  std::unique_ptr<AtomicFileStream> traj;  // streamed to a temporary, renamed when the run ends
  std::vector<TimedRow> timed_rows;
  std::vector<long> nearest_step;  // fixed step with output times: the step of each
  long observer_calls = 0;
  Vec y0;
};

// --times, --log-outputs, --log-first and --frames: which combinations are allowed.
void check_output_modes(SolveRun& run) {
  const SolveOptions& opt = run.opt;
  require_input(opt.times.empty() || opt.log_outputs == 0,
                "--times and --log-outputs both given: choose one");
  require_input(opt.log_outputs >= 0,
                "--log-outputs must be >= 1 (got " + std::to_string(opt.log_outputs) + ")");
  require_input(std::isnan(opt.log_first) || opt.log_outputs > 0,
                "--log-first needs --log-outputs N");
  run.timed = !opt.times.empty() || opt.log_outputs > 0;
  run.times_flag = opt.times.empty() ? "--log-outputs" : "--times";
  require_input(!run.timed || opt.frames == 0,
                run.times_flag + " cannot be combined with --frames");
}

// --t-end; without it the last of --times, else the model's literature end time.
double resolve_t_end(const SolveOptions& opt, const OdeSystem& sys) {
  if (!std::isnan(opt.t_end)) return opt.t_end;
  if (!opt.times.empty()) {
    // The run ends at the last requested time.
    require_input(std::isfinite(opt.times.back()),
                  "--times: " + format_full(opt.times.back()) + " is not a finite time");
    return opt.times.back();
  }
  const auto literature = sys.end_time();
  require_input(literature.has_value(),
                "--t-end is required: model '" + opt.model + "' has no default end time");
  return *literature;
}

// Fixed step with --h. Without it: the integrator's own step control where it has one, else
// the model's suggested step (its CFL limit), else an error.
StepChoice resolve_step(const SolveOptions& opt, const OdeSystem& sys, const Integrator& integ) {
  StepChoice step;
  step.h = opt.h;
  if (std::isnan(step.h)) {
    if (integ.supports_adaptive()) {
      step.adaptive = true;
    } else if ((step.suggested = sys.suggested_step())) {
      step.h = step.suggested->h;
    } else {
      throw BadInput("--h is required: integrator '" + opt.integrator +
                     "' is fixed-step and model '" + opt.model + "' offers no suggested step");
    }
  }
  require_input(step.adaptive || integ.supports_fixed_step(),
                "integrator '" + opt.integrator +
                    "' has no fixed-step mode: omit --h and set --param rtol=R");
  return step;
}

// The requested output times (--times as given, or those of --log-outputs), checked: finite,
// strictly increasing and in (t0, t_end].
std::vector<double> resolve_output_times(const SolveRun& run) {
  const SolveOptions& opt = run.opt;
  const double t0 = run.t0, t_end = run.t_end;
  const std::string& flag = run.times_flag;
  std::vector<double> times = opt.times;
  if (opt.log_outputs > 0) {
    require_input(std::isfinite(t_end) && t_end > t0, "--t-end must be > the model's initial time");
    times = log_output_times(t0, t_end, opt.log_outputs, opt.log_first);
  }
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double t = times[k];
    require_input(std::isfinite(t), flag + ": " + format_full(t) + " is not a finite time");
    require_input(k == 0 || t > times[k - 1], flag + " must be strictly increasing (" +
                                                  format_full(t) + " after " +
                                                  format_full(k ? times[k - 1] : t0) + ")");
  }
  if (!times.empty()) {
    require_input(times.front() > t0, flag + ": " + format_full(times.front()) +
                                          " is not after the model's initial time " +
                                          format_full(t0));
    require_input(times.back() <= t_end,
                  flag + ": " + format_full(times.back()) + " is after " +
                      (std::isnan(opt.t_end)
                           ? "the model's end time " + format_full(t_end) + " (give --t-end)"
                           : "--t-end " + format_full(t_end)));
  }
  return times;
}

// The driver's options; for a fixed step, the step count (a suggested step rounded down so that
// its stability limit holds) and notes on `err` about frames, long runs and the suggested step.
void plan_steps(SolveRun& run, std::ostream& err) {
  const SolveOptions& opt = run.opt;
  FixedStepOptions& fo = run.fo;
  fo.t_end = run.t_end;
  fo.h = run.step.h;
  fo.outputs = run.frames ? opt.frames : opt.outputs;
  if (run.step.adaptive) return;
  const auto& suggested = run.step.suggested;
  if (suggested) {
    // A stability limit must not be exceeded: N = ceil(T/h) steps of T/N <= h (the driver's
    // round(T/h) could make the step up to 1/(2N) larger).
    const double span = run.t_end - run.sys.initial_time();
    require_input(span > 0, "--t-end must be > the model's initial time");
    fo.h = span / std::ceil(span / run.step.h * (1.0 - 1e-12));
  }
  run.n_steps = fixed_step_count(run.sys.initial_time(), run.t_end, fo.h, fo.max_steps);
  if (run.frames && opt.frames > run.n_steps)
    err << "solve: " << opt.frames << " frames requested but the run has " << run.n_steps
        << " steps: one frame per step\n";
  if (run.n_steps > 10'000'000)
    err << "solve: " << run.n_steps << " steps; this may take a while\n";
  if (suggested)
    err << "solve: no --h given: using the model's suggested step h = " << format_full(run.step.h)
        << " (" << suggested->rule << ")\n";
}

// The trajectory file's size, checked before the run: a note when it is large, BadInput when the
// file system holding it has less room than its bound (trajectory_bytes_bound).
void plan_trajectory(const SolveRun& run, std::ostream& err) {
  if (run.traj_path.empty()) return;
  long rows = static_cast<long>(run.times.size());
  if (!run.timed) {
    rows = std::max(1L, run.fo.outputs);
    if (!run.step.adaptive) rows = std::min(rows, run.n_steps);
    rows += 1;
  }
  const double bytes = trajectory_bytes_bound(rows, run.sys.dimension());
  const std::string what =
      "the trajectory file " + run.traj_path + " will hold " + std::to_string(rows) + " rows of " +
      std::to_string(run.sys.dimension() + 1) + " numbers, up to " + format_bytes(bytes);
  const std::string fewer = run.timed ? "fewer output times" : "a smaller --outputs";
  std::error_code ec;
  const auto parent = std::filesystem::absolute(run.traj_path, ec).parent_path();
  const auto space = std::filesystem::space(parent, ec);
  if (!ec)
    require_input(bytes <= static_cast<double>(space.available),
                  "--out: " + what + ", more than the " +
                      format_bytes(static_cast<double>(space.available)) + " free in " +
                      parent.string() + "; give " + fewer + " or another --out");
  if (bytes >= kLargeTrajectoryBytes)
    err << "solve: " << what << " (" << fewer << " writes less)\n";
}

// The output is checked before the run: an unwritable path is bad input now, not after it.
// Output safety: a folder of frames holding solve.json of a different spec, or a trajectory
// file that exists (no spec is recorded beside it), is refused unless --force.
void check_output(const SolveOptions& opt, bool frames, std::ostream& err) {
  if (frames) {
    require_output_dir(opt.out_csv, "--out");
    check_existing_results(opt.out_csv, "solve.json",
                           {"observables.csv", "frames.pvd", "trajectory.csv", "frame_0000.csv"},
                           solve_spec(opt), force_output(), &err);
  } else if (!opt.out_csv.empty()) {
    require_output_file(opt.out_csv, "--out");
    if (std::filesystem::exists(opt.out_csv)) {
      const std::string what = "--out " + opt.out_csv +
                               " exists (a trajectory file records no spec, so solve cannot tell "
                               "whether it holds this run)";
      if (!force_output())
        throw BadInput(what + "; choose another --out or pass --force to replace it");
      err << "note: " << what << ": replacing it (--force)\n";
    }
  }
}

// --frames: the frame writer and DIR/solve.json.
void open_frames(SolveRun& run) {
  const SolveOptions& opt = run.opt;
  require_input(opt.frame_format == "vtu" || opt.frame_format == "vtk",
                "--frame-format must be vtu or vtk (got '" + opt.frame_format + "')");
  run.frame_writer = std::make_unique<FrameWriter>(
      run.sys, opt.out_csv, opt.frame_format == "vtk" ? FrameFormat::vtk : FrameFormat::vtu);
  nlohmann::json meta = run_metadata("solve", solve_spec(opt));
  meta["t_end_used"] = run.t_end;
  meta["h_used"] = run.step.adaptive ? nlohmann::json() : nlohmann::json(run.fo.h);
  write_file_atomic(run.frame_writer->dir() / "solve.json", meta.dump(2) + "\n");
}

void write_traj_row(std::ostream& traj, double t, CVecRef y) {
  traj << format_full(t);
  for (Index i = 0; i < y.size(); ++i) traj << "," << format_full(y[i]);
  traj << "\n";
}

// --times / --log-outputs: one row per requested time. Adaptive: the observer's calls are t0,
// the requested times, then t_end when it is not the last of them. Fixed step: the observer
// sees every step; step j is recorded for each requested time whose nearest step it is.
Observer timed_observer(SolveRun& run) {
  if (!run.step.adaptive) {
    const double h_run = (run.t_end - run.t0) / static_cast<double>(run.n_steps);
    for (const double t : run.times)
      run.nearest_step.push_back(
          std::clamp(std::llround((t - run.t0) / h_run), 0LL, static_cast<long long>(run.n_steps)));
    run.fo.outputs = run.n_steps;  // the observer at every step
  }
  return [&run](double t, CVecRef y) {
    const long call = run.observer_calls++;
    auto& rows = run.timed_rows;
    if (run.step.adaptive) {
      if (call >= 1 && static_cast<std::size_t>(call) <= run.times.size())
        rows.push_back({run.times[static_cast<std::size_t>(call - 1)], t, y});
      return;
    }
    while (rows.size() < run.times.size() && run.nearest_step[rows.size()] == call)
      rows.push_back({run.times[rows.size()], t, y});
  };
}

// The observer: requested times, else the trajectory rows and frames (none when neither).
Observer make_observer(SolveRun& run, std::ostream& err) {
  if (run.timed) return timed_observer(run);
  if (run.traj_path.empty() && !run.frame_writer) return {};
  return [&run, &err](double t, CVecRef y) {
    if (run.traj) write_traj_row(run.traj->stream(), t, y);
    if (run.frame_writer) {
      run.frame_writer->write(t, y);
      err << "solve: frame " << run.frame_writer->frames() - 1 << "/"
          << (run.step.adaptive ? run.opt.frames : std::min(run.opt.frames, run.n_steps))
          << " at t = " << format_short(t, 4) << "\n";
    }
  };
}

// The run itself, recording output rows and frames on the way.
RunResult execute(SolveRun& run, std::ostream& err) {
  if (!run.traj_path.empty()) {
    run.traj = std::make_unique<AtomicFileStream>(run.traj_path);
    std::ostream& traj = run.traj->stream();
    traj << "t";
    for (Index i = 0; i < run.sys.dimension(); ++i) traj << ",y" << i;
    traj << "\n";
  }
  const Observer obs = make_observer(run, err);
  run.y0 = run.sys.initial_state();
  return run.step.adaptive
             ? run_adaptive(run.sys, run.integ, {run.t_end, run.fo.outputs, run.times}, obs)
             : run_fixed_step(run.sys, run.integ, run.fo, obs);
}

// The trajectory file, written whatever the status: the trajectory up to a blow-up is part of
// the result.
void write_trajectory(SolveRun& run) {
  if (!run.traj) return;
  if (run.timed)
    for (const auto& row : run.timed_rows) write_traj_row(run.traj->stream(), row.t, row.y);
  run.traj->commit();
}

// Model, integrator, step, stiffness at t0 and status.
void print_run_header(const SolveRun& run, const RunResult& r, std::ostream& out) {
  const SolveOptions& opt = run.opt;
  const OdeSystem& sys = run.sys;
  out << std::setprecision(17);
  out << "model        " << opt.model;
  for (const auto& [k, v] : opt.params.values()) out << " " << k << "=" << v;
  const auto& info = run.integ.info();
  out << "\nintegrator   " << opt.integrator << " (" << to_string(info.family) << ", order "
      << (info.order ? std::to_string(info.order) : "variable") << ")\n";
  if (run.step.adaptive) {
    out << "steps        adaptive (" << r.stats.steps << " steps to t = " << format_full(run.t_end)
        << ")\n";
    // The run stops exactly at every output time (run_adaptive), which caps its steps: say so,
    // so that an error read here is not taken for the method's own at its tolerance.
    if (!run.times.empty())
      out << "             stopping exactly at each of the " << run.times.size()
          << " output times, which can shorten steps\n";
    else if (run.fo.outputs > 1)
      out << "             stopping exactly at " << run.fo.outputs
          << " equally spaced output times (--outputs): no step longer than "
          << format_short((run.t_end - sys.initial_time()) / static_cast<double>(run.fo.outputs))
          << "; --outputs 1 lets the method choose every step\n";
  } else {
    out << "h            " << format_full(r.h) << " (" << r.n_steps
        << " steps to t = " << format_full(run.t_end) << ")\n";
    if (run.step.suggested)
      out << "             the model's suggested step: " << run.step.suggested->rule << "\n";
  }
  if (const auto rho = sys.stiffness(sys.initial_time(), run.y0)) {
    out << "stiffness    spectral radius ~ " << format_short(*rho) << " at t0";
    if (!run.step.adaptive) out << ", h*rho = " << format_short(*rho * r.h);
    out << "\n";
  }
  out << "status       " << to_string(r.stats.status) << "\n";
  if (!r.stats.message.empty()) out << "message      " << r.stats.message << "\n";
}

// The final state; large states (particle and network models) print their first components. A
// run that ended early holds the state where it stopped, which may lie after the last output
// time it reached (the status message says where).
void print_final_state(const RunResult& r, std::ostream& out) {
  if (r.stats.status == Status::ok)
    out << "\nfinal state at t = " << format_full(r.t) << ":\n";
  else
    out << "\nstate where the run stopped (" << to_string(r.stats.status)
        << "; the last output time it reached is t = " << format_full(r.t)
        << ", the message says where it stopped):\n";
  constexpr Index kPrintMax = 24;
  const Index shown = r.y.size() <= kPrintMax ? r.y.size() : kPrintMax / 2;
  for (Index i = 0; i < shown; ++i) out << "  y" << i << " = " << format_full(r.y[i]) << "\n";
  if (shown < r.y.size())
    out << "  ... (" << r.y.size() - shown << " more of " << r.y.size()
        << " components: --out writes them all)\n";
}

// The table of the states at the requested times (first components of large states).
void print_timed_table(const SolveRun& run, const RunResult& r, std::ostream& out) {
  const auto& times = run.times;
  const auto& rows = run.timed_rows;
  out << "\nstate at " << times.size() << " requested time" << (times.size() == 1 ? "" : "s")
      << (run.step.adaptive ? " (adaptive: the integrator stops exactly at each)"
                            : " (fixed step: the state at the nearest step, whose t is shown)")
      << ":\n\n";
  constexpr Index kColumnsMax = 6;
  const Index dim = run.sys.dimension();
  const Index cols = std::min<Index>(dim, kColumnsMax);
  Table t{{"t_requested", "t"}, {}};
  for (Index i = 0; i < cols; ++i) t.columns.push_back("y" + std::to_string(i));
  for (const auto& row : rows) {
    std::vector<std::string> cells{format_full(row.requested), format_full(row.t)};
    for (Index i = 0; i < cols; ++i) cells.push_back(format_full(row.y[i]));
    t.rows.push_back(cells);
  }
  out << t.to_markdown();
  if (cols < dim)
    out << "(first " << cols << " of " << dim << " components: --out writes them all)\n";
  if (rows.size() < times.size())
    out << "(the run ended at t = " << format_full(r.t) << ": " << rows.size() << " of "
        << times.size() << " requested times reached)\n";
}

// Error against the exact solution, and against the published one (relative error and mescd
// of the IVP test set) when the run ended at its time.
void print_accuracy(const SolveRun& run, const RunResult& r, std::ostream& out) {
  const OdeSystem& sys = run.sys;
  if (sys.has_exact() && r.stats.status == Status::ok) {
    Vec ye(sys.dimension());
    sys.exact(r.t, ye);
    out << "\nerror vs exact solution (max-norm): " << format_short(max_abs_diff(r.y, ye), 6)
        << "\n";
  }
  const auto pub = sys.published_solution();
  if (!(pub && r.stats.status == Status::ok && std::abs(r.t - pub->t) <= 1e-12 * std::abs(pub->t)))
    return;
  // mescd of the IVP test set with atol/rtol from the run's own parameters when it has them.
  const Params& params = run.opt.params;
  double ratio = 0.0;
  if (params.contains("atol") && params.contains("rtol"))
    ratio = params.real("atol") / params.real("rtol");
  double worst_rel = 0.0, worst_mixed = 0.0;
  for (Index i = 0; i < r.y.size(); ++i) {
    const double e = std::abs(r.y[i] - pub->y[i]), a = std::abs(pub->y[i]);
    worst_rel = std::max(worst_rel, a > 0 ? e / a : e);
    worst_mixed = std::max(worst_mixed, e / (ratio + a));
  }
  out << "\npublished solution at t = " << format_full(pub->t) << " (" << pub->source << "):\n"
      << "  max relative error " << format_short(worst_rel, 3) << ", mescd " << std::fixed
      << std::setprecision(2) << -std::log10(std::max(worst_mixed, 1e-300)) << std::defaultfloat
      << std::setprecision(6) << " (atol/rtol = " << format_short(ratio) << ")\n";
}

// Constraint residual, invariants and observables, initial and final.
void print_conserved(const SolveRun& run, const RunResult& r, std::ostream& out) {
  const OdeSystem& sys = run.sys;
  const Vec& y0 = run.y0;
  if (sys.has_constraints()) {
    out << "\nconstraint residual max|C|: initial " << format_short(sys.constraint_residual(y0))
        << ", final " << format_short(sys.constraint_residual(r.y)) << "\n";
  }
  const auto invariants = sys.invariants();
  if (!invariants.empty()) {
    // The change relative to |initial|, or absolute (marked) when the initial value is 0 or the
    // invariant's zero is arbitrary (Invariant::arbitrary_zero, said below the table).
    out << "\ninvariants          initial                  final                    change\n";
    std::string notes;
    for (const auto& inv : invariants) {
      const double a = inv.value(sys.initial_time(), y0), b = inv.value(r.t, r.y);
      const bool relative = a != 0 && inv.arbitrary_zero.empty();
      out << "  " << std::left << std::setw(18) << inv.name << std::setw(25) << format_full(a)
          << std::setw(25) << format_full(b) << std::right
          << format_short(relative ? (b - a) / std::abs(a) : b - a)
          << (relative ? " (relative)" : " (absolute)") << "\n";
      if (!inv.arbitrary_zero.empty())
        notes += "  " + inv.name + ": absolute change, its zero is arbitrary (" +
                 inv.arbitrary_zero + ")\n";
    }
    out << notes;
  }
  const auto observables = sys.observables();
  if (!observables.empty()) {
    out << "\nobservables         initial                  final\n";
    for (const auto& o : observables) {
      out << "  " << std::left << std::setw(18) << o.name << std::setw(25)
          << format_full(o.value(sys.initial_time(), y0)) << format_full(o.value(r.t, r.y))
          << std::right << "\n";
    }
  }
}

// The files of --frames, and plots of the last frame (pressure) and, for a dam break, of the
// front against K&O.
void print_frames(const SolveRun& run, const RunResult& r, std::ostream& out, std::ostream& err) {
  const SolveOptions& opt = run.opt;
  const OdeSystem& sys = run.sys;
  const FrameWriter& writer = *run.frame_writer;
  const auto& dir = writer.dir();
  out << "\nframes: " << writer.frames() << " rows in " << (dir / "observables.csv").string();
  if (sys.has_particles())
    out << ", VTK frames in " << dir.string() << "/frame_*."
        << (opt.frame_format == "vtk" ? "vtk" : "vtu (frames.pvd)");
  if (sys.has_grid())
    out << ", VTK image data in " << dir.string() << "/frame_*."
        << (opt.frame_format == "vtk" ? "vtk" : "vti (frames.pvd)");
  for (const Profile& p : sys.profiles(r.t, r.y)) out << ", " << (dir / (p.name + ".csv")).string();
  out << "\n";
  if (sys.has_particles() && writer.frames() > 0) {
    char last[32];
    std::snprintf(last, sizeof last, "frame_%04ld.csv", writer.frames() - 1);
    const std::string title = opt.model + ", " + opt.integrator + ", t = " + format_short(r.t, 4);
    if (run_plot("sph_frame.gp", dir / "frame_last",
                 {{"csvfile", (dir / last).string()}, {"ttl", title}}, {}, PlotOptions{}, err))
      out << "plot: " << (dir / "frame_last.png").string() << "\n";
  }
  const auto cols = writer.columns();
  if (std::find(cols.begin(), cols.end(), "Z") != cols.end() &&
      run_plot("dam_break_front.gp", dir / "front",
               {{"csvfile", (dir / "observables.csv").string()},
                {"ttl", opt.model + ", " + opt.integrator}},
               {}, PlotOptions{}, err))
    out << "plot: " << (dir / "front.png").string() << "\n";
}

// The summary on `out`.
void print_summary(const SolveRun& run, const RunResult& r, std::ostream& out, std::ostream& err) {
  print_run_header(run, r, out);
  print_final_state(r, out);
  if (run.timed) print_timed_table(run, r, out);
  print_accuracy(run, r, out);
  print_conserved(run, r, out);
  out << "\nstatistics:\n";
  print_stats_table(out, r.stats);
  if (!run.traj_path.empty()) out << "\ntrajectory: " << run.traj_path << "\n";
  if (run.frame_writer) print_frames(run, r, out, err);
}

}  // namespace

nlohmann::json solve_spec(const SolveOptions& opt) {
  return {{"model", opt.model},
          {"params", opt.params.values()},
          {"integrator", opt.integrator},
          {"h", opt.h},
          {"t_end", opt.t_end},
          {"frames", opt.frames},
          {"frame_format", opt.frame_format}};
}

void cmd_solve(const SolveOptions& given, std::ostream& out, std::ostream& err) {
  require_input(!given.model.empty(), "--model is required");
  require_input(!given.integrator.empty(), "--integrator is required");
  // A method file given by path is registered and named by its method (catalog.hpp).
  SolveOptions opt = given;
  opt.integrator = resolve_integrator_tokens({given.integrator}).front();
  require_input(opt.outputs >= 1,
                "--outputs must be >= 1 (got " + std::to_string(opt.outputs) + ")");
  Setup setup = make_setup(opt.model, {opt.integrator}, opt.params);
  SolveRun run(opt, *setup.model, *setup.integrators.front());
  check_output_modes(run);
  run.t_end = resolve_t_end(opt, run.sys);
  run.step = resolve_step(opt, run.sys, run.integ);
  run.t0 = run.sys.initial_time();
  run.times = resolve_output_times(run);
  require_input(opt.frames >= 0, "--frames must be >= 0 (got " + std::to_string(opt.frames) + ")");
  run.frames = opt.frames > 0;
  require_input(!run.frames || !opt.out_csv.empty(),
                "--frames needs --out DIR (the output directory)");
  plan_steps(run, err);
  check_output(opt, run.frames, err);
  // The trajectory: the --out file, or with --frames DIR/trajectory.csv for models without
  // particles or grid (those write frames instead).
  run.traj_path = !run.frames ? opt.out_csv
                  : run.sys.has_particles() || run.sys.has_grid()
                      ? ""
                      : (std::filesystem::path(opt.out_csv) / "trajectory.csv").string();
  plan_trajectory(run, err);
  if (run.frames) open_frames(run);
  const RunResult r = execute(run, err);
  write_trajectory(run);
  print_summary(run, r, out, err);
}

double trajectory_bytes_bound(long rows, Index dimension) {
  // Header "t,y0,y1,...": 2 + the digits of each index and its ",y".
  double header = 2;
  for (Index i = 0; i < dimension; ++i) header += 2 + std::to_string(i).size();
  // A number is at most 24 characters in the shortest round-trip form (sign, 17 digits, point,
  // "e-308"), plus its separator (the comma, or the row's newline).
  return header + static_cast<double>(rows) * 25.0 * static_cast<double>(dimension + 1);
}

std::vector<double> parse_times(const std::string& list) {
  return parse_real_list(list, "--times");
}

std::vector<double> log_output_times(double t0, double t_end, long n, double first) {
  require_input(n >= 1, "--log-outputs must be >= 1 (got " + std::to_string(n) + ")");
  const double span = t_end - t0;
  require_input(std::isfinite(span) && span > 0, "--t-end must be > the model's initial time");
  if (n == 1) {
    require_input(std::isnan(first), "--log-first needs --log-outputs >= 2");
    return {t_end};
  }
  // t_k = t0 + span / ratio^((N-k)/(N-1)) with ratio = span/(first - t0): by default
  // ratio = 10^(N-1) and t_k = t0 + span/10^(N-k), exact decades when span is one.
  const bool given = !std::isnan(first);
  if (given)
    require_input(std::isfinite(first) && first > t0 && first < t_end,
                  "--log-first must be after the model's initial time " + format_full(t0) +
                      " and before t_end " + format_full(t_end) + " (got " + format_full(first) +
                      ")");
  std::vector<double> out;
  for (long k = 1; k <= n; ++k) {
    const double down = given ? std::pow(span / (first - t0),
                                         static_cast<double>(n - k) / static_cast<double>(n - 1))
                              : std::pow(10.0, static_cast<double>(n - k));
    const double t = k == n ? t_end : k == 1 && given ? first : t0 + span / down;
    require_input(std::isfinite(t) && t > (out.empty() ? t0 : out.back()),
                  "--log-outputs " + std::to_string(n) +
                      ": the output times are not increasing after t0 = " + format_full(t0) +
                      " (spacing below the resolution of t; give fewer outputs or --log-first)");
    out.push_back(t);
  }
  return out;
}

}  // namespace stiffbench

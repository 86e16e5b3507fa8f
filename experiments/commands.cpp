#include "experiments/commands.hpp"
#include "experiments/study.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/catalog.hpp"
#include "experiments/frames.hpp"
#include "experiments/plotting.hpp"
#include "experiments/work_precision.hpp"

namespace stiffbench {

namespace {

void list_models(std::ostream& out) {
  Table t{{"model", "kind", "exact", "parameters", "description"}, {}};
  for (const auto& e : model_registry().entries()) {
    std::vector<std::string> keys;
    for (const auto& p : e.params) keys.push_back(p.key);
    t.rows.push_back({e.info.name, e.info.mechanical ? "mechanical" : "first-order",
                      e.info.exact ? "yes" : "no", join(keys, " "), e.info.description});
  }
  out << t.to_markdown();
}

// "fixed", "adaptive" or "fixed, adaptive": what a default-constructed instance supports.
std::string step_modes(const IntegratorRegistry::Entry& e) {
  const auto integ = integrator_registry().create(e.info.name, Params{});
  std::vector<std::string> modes;
  if (integ->supports_fixed_step()) modes.push_back("fixed");
  if (integ->supports_adaptive()) modes.push_back("adaptive");
  return join(modes, ", ");
}

void list_integrators(std::ostream& out) {
  Table t{{"integrator", "family", "kind", "order", "stages", "step", "requires", "description"},
          {}};
  for (const auto& e : integrator_registry().entries()) {
    const MethodInfo& m = e.info;
    t.rows.push_back({m.name, to_string(m.family), m.kind.empty() ? "-" : m.kind,
                      m.order ? std::to_string(m.order) : "variable",
                      m.stages ? std::to_string(m.stages) : "variable", step_modes(e),
                      describe_requirements(m.requires_), m.description});
  }
  out << t.to_markdown();
}

Table experiments_table() {
  Table t{{"experiment", "writes", "description"}, {}};
  t.rows.push_back({"solve",
                    "trajectory CSV (t,y0,y1,...); with --frames: VTK/CSV frames, observables.csv",
                    "one run (fixed step, the model's suggested step, or adaptive); final state, "
                    "invariants, observables and statistics; --times/--log-outputs: the state at "
                    "given times (exact stops when adaptive, nearest step when fixed)"});
  t.rows.push_back({"convergence", "convergence.{csv,md,json,png}; reference/<hash>.csv",
                    "global error at t_end vs h, observed orders; a non-exact reference is "
                    "cached in the output folder"});
  t.rows.push_back(
      {"local-error", "local_error.{csv,md,json,png}", "error of one step vs h, observed slopes"});
  t.rows.push_back({"work-precision", "work_precision.{csv,md,json,png}",
                    "error at t_end against work: h ladder for fixed-step methods, tolerance "
                    "ladder for references"});
  t.rows.push_back({"stability", "stability.{csv,md,json,png}",
                    "largest stable fixed step per integrator (bisection) against linear theory; "
                    "--sweep over a stiffness parameter with log-log slope"});
  t.rows.push_back({"region", "region.{csv,md,json,png}, region_limits.csv",
                    "stability region boundaries (amplification 1) from the coefficients, axis and "
                    "oscillator limits, A-stability"});
  t.rows.push_back({"energy", "energy.{csv,md,json,png}, energy_summary.csv",
                    "relative invariant error at every step, sampled; max, final, drift rate, "
                    "growth ratio"});
  t.rows.push_back({"plot", "NAME.png (and .svg) next to each CSV",
                    "redraw the plots of an output folder from its CSV files"});
  t.rows.push_back({"report", "DIR/REPORT.md and one folder per study",
                    "the default suite: convergence, local error, energy drift, stability "
                    "limits and regions, work-precision"});
  // Studies registered from outside the library (register_study).
  for (const auto& k : study_kinds()) {
    bool listed = false;
    for (const auto& row : t.rows) listed = listed || row[0] == k.name;
    if (!listed) t.rows.push_back({k.name, k.stem + ".{csv,md,json,png}", k.summary});
  }
  return t;
}

void list_experiments(std::ostream& out) { out << experiments_table().to_markdown(); }

std::string count_or_variable(int n) { return n ? std::to_string(n) : "variable"; }

void print_params(const std::vector<ParamSpec>& params, std::ostream& out) {
  if (params.empty()) {
    out << "\nParameters: none\n";
    return;
  }
  out << "\nParameters (--param key=value):\n\n";
  // The range column: what resolve_params accepts for a numeric parameter.
  Table t{{"key", "type", "default", "range", "meaning"}, {}};
  for (const auto& p : params) {
    std::string help = p.help;
    if (!p.choices.empty()) help += " (one of: " + join(p.choices, ", ") + ")";
    const bool numeric = p.type == ParamType::real || p.type == ParamType::integer;
    t.rows.push_back(
        {p.key, to_string(p.type), p.default_value, numeric ? p.bounds.to_string() : "", help});
  }
  out << t.to_markdown();
}

}  // namespace

void cmd_list(const std::string& what, std::ostream& out) {
  if (what.empty() || what == "models") {
    if (what.empty()) out << "Models:\n\n";
    list_models(out);
  }
  if (what.empty() || what == "integrators") {
    if (what.empty()) out << "\nIntegrators:\n\n";
    list_integrators(out);
  }
  if (what.empty() || what == "experiments") {
    if (what.empty()) out << "\nExperiments:\n\n";
    list_experiments(out);
  }
}

void cmd_describe(const std::string& name, std::ostream& out) {
  if (const auto* m = model_registry().find(name)) {
    out << "model " << name << ": " << m->info.description << "\n";
    out << "kind: " << (m->info.mechanical ? "mechanical (y = [x; v])" : "first-order") << "\n";
    out << "exact solution: " << (m->info.exact ? "yes" : "no") << "\n";
    out << "source: " << m->info.source << "\n";
    const auto sys = model_registry().create(name, Params{});
    out << "dimension (defaults): " << sys->dimension() << "\n";
    std::vector<std::string> inv;
    for (const auto& i : sys->invariants()) inv.push_back(i.name);
    out << "invariants: " << (inv.empty() ? "none" : join(inv)) << "\n";
    out << "analytic Jacobian: " << (sys->has_jacobian() ? "yes" : "no") << "\n";
    if (const auto s = sys->suggested_step())
      out << "suggested step (defaults): " << format_short(s->h, 4) << " (" << s->rule << ")\n";
    std::vector<std::string> obs;
    for (const auto& o : sys->observables()) obs.push_back(o.name);
    if (!obs.empty()) out << "observables: " << join(obs) << "\n";
    print_params(m->params, out);
    return;
  }
  if (const auto* e = integrator_registry().find(name)) {
    const MethodInfo& i = e->info;
    out << "integrator " << name << ": " << i.description << "\n";
    out << "family: " << to_string(i.family);
    if (!i.kind.empty()) out << " (" << i.kind << ")";
    out << "\nreference: " << (i.reference.empty() ? "none given" : i.reference)
        << "\nstep: " << step_modes(*e) << "\norder: " << count_or_variable(i.order)
        << "\nevaluations per step: " << count_or_variable(i.stages)
        << "\nrequires: " << describe_requirements(i.requires_) << "\n";
    print_params(e->params, out);
    return;
  }
  if (const StudyKind* k = find_study(name)) {
    describe_study(*k, out);
    out << "\nflags: stiffbench " << name << " --help\n";
    return;
  }
  std::vector<std::string> experiments;
  for (const auto& row : experiments_table().rows) {
    experiments.push_back(row[0]);
    if (row[0] != name) continue;
    out << "experiment " << name << ": " << row[2] << "\n";
    out << "writes: " << row[1] << "\n";
    out << "flags: stiffbench " << name << " --help\n";
    return;
  }
  std::vector<std::string> all = model_registry().names();
  for (const auto& n : integrator_registry().names()) all.push_back(n);
  for (const auto& n : experiments) all.push_back(n);
  throw BadInput("unknown name '" + name + "'" + did_you_mean(name, all) + ": not a model (" +
                 join(model_registry().names()) + "), an integrator (" +
                 join(integrator_registry().names()) + ") nor an experiment (" + join(experiments) +
                 ")");
}

nlohmann::json solve_spec(const SolveOptions& opt) {
  return {{"model", opt.model},
          {"params", opt.params.values()},
          {"integrator", opt.integrator},
          {"h", opt.h},
          {"t_end", opt.t_end},
          {"frames", opt.frames},
          {"frame_format", opt.frame_format}};
}

void cmd_solve(const SolveOptions& opt, std::ostream& out, std::ostream& err) {
  require_input(!opt.model.empty(), "--model is required");
  require_input(!opt.integrator.empty(), "--integrator is required");
  require_input(opt.outputs >= 1,
                "--outputs must be >= 1 (got " + std::to_string(opt.outputs) + ")");
  Setup setup = make_setup(opt.model, {opt.integrator}, opt.params);
  const OdeSystem& sys = *setup.model;
  Integrator& integ = *setup.integrators.front();
  require_input(opt.times.empty() || opt.log_outputs == 0,
                "--times and --log-outputs both given: choose one");
  require_input(opt.log_outputs >= 0,
                "--log-outputs must be >= 1 (got " + std::to_string(opt.log_outputs) + ")");
  require_input(std::isnan(opt.log_first) || opt.log_outputs > 0,
                "--log-first needs --log-outputs N");
  const bool timed = !opt.times.empty() || opt.log_outputs > 0;
  const std::string times_flag = opt.times.empty() ? "--log-outputs" : "--times";
  require_input(!timed || opt.frames == 0, times_flag + " cannot be combined with --frames");
  double t_end = opt.t_end;
  if (std::isnan(t_end) && !opt.times.empty()) {
    // The run ends at the last requested time.
    require_input(std::isfinite(opt.times.back()),
                  "--times: " + format_full(opt.times.back()) + " is not a finite time");
    t_end = opt.times.back();
  } else if (std::isnan(t_end)) {
    const auto literature = sys.end_time();
    require_input(literature.has_value(),
                  "--t-end is required: model '" + opt.model + "' has no default end time");
    t_end = *literature;
  }
  // Fixed step with --h. Without it: the integrator's own step control where it has one, else
  // the model's suggested step (its CFL limit), else an error.
  double h = opt.h;
  std::optional<SuggestedStep> suggested;
  bool adaptive = false;
  if (std::isnan(h)) {
    if (integ.supports_adaptive()) {
      adaptive = true;
    } else if ((suggested = sys.suggested_step())) {
      h = suggested->h;
    } else {
      throw BadInput("--h is required: integrator '" + opt.integrator +
                     "' is fixed-step and model '" + opt.model + "' offers no suggested step");
    }
  }
  require_input(adaptive || integ.supports_fixed_step(),
                "integrator '" + opt.integrator +
                    "' has no fixed-step mode: omit --h and set --param rtol=R");
  const double t0 = sys.initial_time();
  std::vector<double> times = opt.times;
  if (opt.log_outputs > 0) {
    require_input(std::isfinite(t_end) && t_end > t0, "--t-end must be > the model's initial time");
    times = log_output_times(t0, t_end, opt.log_outputs, opt.log_first);
  }
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double t = times[k];
    require_input(std::isfinite(t), times_flag + ": " + format_full(t) + " is not a finite time");
    require_input(k == 0 || t > times[k - 1], times_flag + " must be strictly increasing (" +
                                                  format_full(t) + " after " +
                                                  format_full(k ? times[k - 1] : t0) + ")");
  }
  if (!times.empty()) {
    require_input(times.front() > t0, times_flag + ": " + format_full(times.front()) +
                                          " is not after the model's initial time " +
                                          format_full(t0));
    require_input(times.back() <= t_end,
                  times_flag + ": " + format_full(times.back()) + " is after " +
                      (std::isnan(opt.t_end)
                           ? "the model's end time " + format_full(t_end) + " (give --t-end)"
                           : "--t-end " + format_full(t_end)));
  }
  require_input(opt.frames >= 0, "--frames must be >= 0 (got " + std::to_string(opt.frames) + ")");
  const bool frames = opt.frames > 0;
  require_input(!frames || !opt.out_csv.empty(), "--frames needs --out DIR (the output directory)");
  FixedStepOptions fo;
  fo.t_end = t_end;
  fo.h = h;
  fo.outputs = frames ? opt.frames : opt.outputs;
  long n_steps = 0;
  if (!adaptive) {
    if (suggested) {
      // A stability limit must not be exceeded: N = ceil(T/h) steps of T/N <= h (the driver's
      // round(T/h) could make the step up to 1/(2N) larger).
      const double span = t_end - sys.initial_time();
      require_input(span > 0, "--t-end must be > the model's initial time");
      fo.h = span / std::ceil(span / h * (1.0 - 1e-12));
    }
    n_steps = fixed_step_count(sys.initial_time(), t_end, fo.h, fo.max_steps);
    if (frames && opt.frames > n_steps)
      err << "solve: " << opt.frames << " frames requested but the run has " << n_steps
          << " steps: one frame per step\n";
    if (n_steps > 10'000'000) err << "solve: " << n_steps << " steps; this may take a while\n";
    if (suggested)
      err << "solve: no --h given: using the model's suggested step h = " << format_full(h) << " ("
          << suggested->rule << ")\n";
  }

  // Trajectory CSV: the --out file, or DIR/trajectory.csv with --frames for models without
  // particles (particle models write VTK frames instead).
  std::unique_ptr<FrameWriter> frame_writer;
  std::string traj_path = opt.out_csv;
  // The output is checked before the run: an unwritable path is bad input now, not after it.
  // Output safety: a folder of frames holding solve.json of a different spec, or a trajectory
  // file that exists (no spec is recorded beside it), is refused unless --force.
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
  if (frames) {
    require_input(opt.frame_format == "vtu" || opt.frame_format == "vtk",
                  "--frame-format must be vtu or vtk (got '" + opt.frame_format + "')");
    frame_writer = std::make_unique<FrameWriter>(
        sys, opt.out_csv, opt.frame_format == "vtk" ? FrameFormat::vtk : FrameFormat::vtu);
    nlohmann::json meta = run_metadata("solve", solve_spec(opt));
    meta["t_end_used"] = t_end;
    meta["h_used"] = adaptive ? nlohmann::json() : nlohmann::json(fo.h);
    write_file_atomic(frame_writer->dir() / "solve.json", meta.dump(2) + "\n");
    traj_path = sys.has_particles() || sys.has_grid()
                    ? ""
                    : (frame_writer->dir() / "trajectory.csv").string();
  }
  std::ostringstream traj;
  if (!traj_path.empty()) {
    traj << "t";
    for (Index i = 0; i < sys.dimension(); ++i) traj << ",y" << i;
    traj << "\n";
  }
  // --times / --log-outputs: one row per requested time. Adaptive: the observer's calls are t0,
  // the requested times, then t_end when it is not the last of them. Fixed step: the observer
  // sees every step; step j is recorded for each requested time whose nearest step it is.
  struct TimedRow {
    double requested, t;
    Vec y;
  };
  std::vector<TimedRow> timed_rows;
  std::vector<long> nearest_step;
  if (timed && !adaptive) {
    const double h_run = (t_end - t0) / static_cast<double>(n_steps);
    for (const double t : times)
      nearest_step.push_back(
          std::clamp(std::llround((t - t0) / h_run), 0LL, static_cast<long long>(n_steps)));
    fo.outputs = n_steps;  // the observer at every step
  }
  long observer_calls = 0;
  Observer obs;
  if (timed) {
    obs = [&](double t, CVecRef y) {
      const long call = observer_calls++;
      if (adaptive) {
        if (call >= 1 && static_cast<std::size_t>(call) <= times.size())
          timed_rows.push_back({times[static_cast<std::size_t>(call - 1)], t, y});
        return;
      }
      while (timed_rows.size() < times.size() && nearest_step[timed_rows.size()] == call)
        timed_rows.push_back({times[timed_rows.size()], t, y});
    };
  } else if (!traj_path.empty() || frame_writer) {
    obs = [&](double t, CVecRef y) {
      if (!traj_path.empty()) {
        traj << format_full(t);
        for (Index i = 0; i < y.size(); ++i) traj << "," << format_full(y[i]);
        traj << "\n";
      }
      if (frame_writer) {
        frame_writer->write(t, y);
        err << "solve: frame " << frame_writer->frames() - 1 << "/"
            << (adaptive ? opt.frames : std::min(opt.frames, n_steps))
            << " at t = " << format_short(t, 4) << "\n";
      }
    };
  }
  const Vec y0 = sys.initial_state();
  const RunResult r = adaptive ? run_adaptive(sys, integ, {t_end, fo.outputs, times}, obs)
                               : run_fixed_step(sys, integ, fo, obs);
  if (timed && !traj_path.empty()) {
    for (const auto& row : timed_rows) {
      traj << format_full(row.t);
      for (Index i = 0; i < row.y.size(); ++i) traj << "," << format_full(row.y[i]);
      traj << "\n";
    }
  }
  if (!traj_path.empty()) {
    // Written whatever the status: the trajectory up to a blow-up is part of the result.
    write_file_atomic(traj_path, traj.str());
  }

  out << std::setprecision(17);
  out << "model        " << opt.model;
  for (const auto& [k, v] : opt.params.values()) out << " " << k << "=" << v;
  out << "\nintegrator   " << opt.integrator << " (" << to_string(integ.info().family) << ", order "
      << (integ.info().order ? std::to_string(integ.info().order) : "variable") << ")\n";
  if (adaptive) {
    out << "steps        adaptive (" << r.stats.steps << " steps to t = " << format_full(t_end)
        << ")\n";
  } else {
    out << "h            " << format_full(r.h) << " (" << r.n_steps
        << " steps to t = " << format_full(t_end) << ")\n";
    if (suggested) out << "             the model's suggested step: " << suggested->rule << "\n";
  }
  if (const auto rho = sys.stiffness(sys.initial_time(), y0)) {
    out << "stiffness    spectral radius ~ " << format_short(*rho) << " at t0";
    if (!adaptive) out << ", h*rho = " << format_short(*rho * r.h);
    out << "\n";
  }
  out << "status       " << to_string(r.stats.status) << "\n";
  if (!r.stats.message.empty()) out << "message      " << r.stats.message << "\n";
  out << "\nfinal state at t = " << format_full(r.t) << ":\n";
  // Large states (particle and network models) print their first components only.
  constexpr Index kPrintMax = 24;
  const Index shown = r.y.size() <= kPrintMax ? r.y.size() : kPrintMax / 2;
  for (Index i = 0; i < shown; ++i) out << "  y" << i << " = " << format_full(r.y[i]) << "\n";
  if (shown < r.y.size())
    out << "  ... (" << r.y.size() - shown << " more of " << r.y.size()
        << " components: --out writes them all)\n";
  if (timed) {
    out << "\nstate at " << times.size() << " requested time" << (times.size() == 1 ? "" : "s")
        << (adaptive ? " (adaptive: the integrator stops exactly at each)"
                     : " (fixed step: the state at the nearest step, whose t is shown)")
        << ":\n\n";
    constexpr Index kColumnsMax = 6;
    const Index cols = std::min<Index>(sys.dimension(), kColumnsMax);
    Table t{{"t_requested", "t"}, {}};
    for (Index i = 0; i < cols; ++i) t.columns.push_back("y" + std::to_string(i));
    for (const auto& row : timed_rows) {
      std::vector<std::string> cells{format_full(row.requested), format_full(row.t)};
      for (Index i = 0; i < cols; ++i) cells.push_back(format_full(row.y[i]));
      t.rows.push_back(cells);
    }
    out << t.to_markdown();
    if (cols < sys.dimension())
      out << "(first " << cols << " of " << sys.dimension()
          << " components: --out writes them all)\n";
    if (timed_rows.size() < times.size())
      out << "(the run ended at t = " << format_full(r.t) << ": " << timed_rows.size() << " of "
          << times.size() << " requested times reached)\n";
  }
  if (sys.has_exact() && r.stats.status == Status::ok) {
    Vec ye(sys.dimension());
    sys.exact(r.t, ye);
    out << "\nerror vs exact solution (max-norm): " << format_short(max_abs_diff(r.y, ye), 6)
        << "\n";
  }
  if (const auto pub = sys.published_solution();
      pub && r.stats.status == Status::ok && std::abs(r.t - pub->t) <= 1e-12 * std::abs(pub->t)) {
    // mescd of the IVP test set with atol/rtol from the run's own parameters when it has them.
    double ratio = 0.0;
    if (opt.params.contains("atol") && opt.params.contains("rtol"))
      ratio = opt.params.real("atol") / opt.params.real("rtol");
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
  if (sys.has_constraints()) {
    out << "\nconstraint residual max|C|: initial " << format_short(sys.constraint_residual(y0))
        << ", final " << format_short(sys.constraint_residual(r.y)) << "\n";
  }
  const auto invariants = sys.invariants();
  if (!invariants.empty()) {
    out << "\ninvariants          initial                  final                    rel. change\n";
    for (const auto& inv : invariants) {
      const double a = inv.value(sys.initial_time(), y0), b = inv.value(r.t, r.y);
      out << "  " << std::left << std::setw(18) << inv.name << std::setw(25) << format_full(a)
          << std::setw(25) << format_full(b) << std::right
          << format_short(a != 0 ? (b - a) / std::abs(a) : b - a) << "\n";
    }
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
  out << "\nstatistics:\n";
  print_stats_table(out, r.stats);
  if (!traj_path.empty()) out << "\ntrajectory: " << traj_path << "\n";
  if (frame_writer) {
    const auto& dir = frame_writer->dir();
    out << "\nframes: " << frame_writer->frames() << " rows in "
        << (dir / "observables.csv").string();
    if (sys.has_particles())
      out << ", VTK frames in " << dir.string() << "/frame_*."
          << (opt.frame_format == "vtk" ? "vtk" : "vtu (frames.pvd)");
    if (sys.has_grid())
      out << ", VTK image data in " << dir.string() << "/frame_*."
          << (opt.frame_format == "vtk" ? "vtk" : "vti (frames.pvd)");
    for (const Profile& p : sys.profiles(r.t, r.y))
      out << ", " << (dir / (p.name + ".csv")).string();
    out << "\n";
    // Plots of the last frame (pressure) and, for a dam break, of the front against K&O.
    if (sys.has_particles() && frame_writer->frames() > 0) {
      char last[32];
      std::snprintf(last, sizeof last, "frame_%04ld.csv", frame_writer->frames() - 1);
      const std::string title = opt.model + ", " + opt.integrator + ", t = " + format_short(r.t, 4);
      if (run_plot("sph_frame.gp", dir / "frame_last",
                   {{"csvfile", (dir / last).string()}, {"ttl", title}}, {}, PlotOptions{}, err))
        out << "plot: " << (dir / "frame_last.png").string() << "\n";
    }
    const auto cols = frame_writer->columns();
    if (std::find(cols.begin(), cols.end(), "Z") != cols.end() &&
        run_plot("dam_break_front.gp", dir / "front",
                 {{"csvfile", (dir / "observables.csv").string()},
                  {"ttl", opt.model + ", " + opt.integrator}},
                 {}, PlotOptions{}, err))
      out << "plot: " << (dir / "front.png").string() << "\n";
  }
}

std::vector<double> parse_times(const std::string& list) {
  std::vector<double> out;
  for (const auto& item : split_list(list, "--times")) {
    char* end = nullptr;
    const double t = std::strtod(item.c_str(), &end);
    require_input(end != item.c_str() && *end == '\0',
                  "--times: '" + item + "' is not a number (expected t1,t2,...)");
    out.push_back(t);
  }
  return out;
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

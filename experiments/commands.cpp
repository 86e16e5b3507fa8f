#include "experiments/commands.hpp"

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

void list_integrators(std::ostream& out) {
  Table t{{"integrator", "family", "order", "stages", "requires", "description"}, {}};
  for (const auto& e : integrator_registry().entries()) {
    const MethodInfo& m = e.info;
    t.rows.push_back({m.name, to_string(m.family), m.order ? std::to_string(m.order) : "variable",
                      m.stages ? std::to_string(m.stages) : "variable",
                      describe_requirements(m.requires_), m.description});
  }
  out << t.to_markdown();
}

void list_experiments(std::ostream& out) {
  Table t{{"experiment", "writes", "description"}, {}};
  t.rows.push_back({"solve",
                    "trajectory CSV (t,y0,y1,...); with --frames: VTK/CSV frames, observables.csv",
                    "one run (fixed step, the model's suggested step, or adaptive); final state, "
                    "invariants, observables and statistics"});
  t.rows.push_back(
      {"convergence", "convergence.{csv,md,json}", "global error at t_end vs h, observed orders"});
  t.rows.push_back(
      {"local-error", "local_error.{csv,md,json}", "error of one step vs h, observed slopes"});
  t.rows.push_back({"work-precision", "work_precision.{csv,md,json}",
                    "error at t_end against work: h ladder for fixed-step methods, tolerance "
                    "ladder for references"});
  t.rows.push_back({"report", "DIR/REPORT.md and one folder per study", "the default suite"});
  out << t.to_markdown();
}

void print_params(const std::vector<ParamSpec>& params, std::ostream& out) {
  if (params.empty()) {
    out << "\nParameters: none\n";
    return;
  }
  out << "\nParameters (--param key=value):\n\n";
  Table t{{"key", "type", "default", "meaning"}, {}};
  for (const auto& p : params) {
    std::string help = p.help;
    if (!p.choices.empty()) help += " (one of: " + join(p.choices, ", ") + ")";
    t.rows.push_back({p.key, to_string(p.type), p.default_value, help});
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
    out << "family: " << to_string(i.family) << "\norder: " << i.order
        << "\nevaluations per step: " << i.stages
        << "\nrequires: " << describe_requirements(i.requires_) << "\n";
    print_params(e->params, out);
    return;
  }
  throw BadInput("unknown name '" + name + "': not a model (" + join(model_registry().names()) +
                 ") nor an integrator (" + join(integrator_registry().names()) + ")");
}

void cmd_solve(const SolveOptions& opt, std::ostream& out, std::ostream& err) {
  require_input(!opt.model.empty(), "--model is required");
  require_input(!opt.integrator.empty(), "--integrator is required");
  require_input(opt.outputs >= 1,
                "--outputs must be >= 1 (got " + std::to_string(opt.outputs) + ")");
  Setup setup = make_setup(opt.model, {opt.integrator}, opt.params);
  const OdeSystem& sys = *setup.model;
  Integrator& integ = *setup.integrators.front();
  double t_end = opt.t_end;
  if (std::isnan(t_end)) {
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
  if (frames) {
    require_input(opt.frame_format == "vtu" || opt.frame_format == "vtk",
                  "--frame-format must be vtu or vtk (got '" + opt.frame_format + "')");
    frame_writer = std::make_unique<FrameWriter>(
        sys, opt.out_csv, opt.frame_format == "vtk" ? FrameFormat::vtk : FrameFormat::vtu);
    traj_path = sys.has_particles() ? "" : (frame_writer->dir() / "trajectory.csv").string();
  }
  std::ostringstream traj;
  if (!traj_path.empty()) {
    traj << "t";
    for (Index i = 0; i < sys.dimension(); ++i) traj << ",y" << i;
    traj << "\n";
  }
  Observer obs;
  if (!traj_path.empty() || frame_writer) {
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
  const RunResult r = adaptive ? run_adaptive(sys, integ, {t_end, fo.outputs}, obs)
                               : run_fixed_step(sys, integ, fo, obs);
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
  if (sys.has_exact() && r.stats.status == Status::ok) {
    Vec ye(sys.dimension());
    sys.exact(r.t, ye);
    out << "\nerror vs exact solution (max-norm): " << format_short(max_abs_diff(r.y, ye), 6)
        << "\n";
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

}  // namespace stiffbench

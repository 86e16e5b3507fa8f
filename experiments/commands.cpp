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

namespace {
bool run_gnuplot(const std::string& script,
                 const std::vector<std::pair<std::string, std::string>>& vars, std::ostream& err);
}  // namespace

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
      if (run_gnuplot("sph_frame.gp",
                      {{"csvfile", (dir / last).string()},
                       {"outfile", (dir / "frame_last.png").string()},
                       {"ttl", title}},
                      err))
        out << "plot: " << (dir / "frame_last.png").string() << "\n";
    }
    const auto cols = frame_writer->columns();
    if (std::find(cols.begin(), cols.end(), "Z") != cols.end() &&
        run_gnuplot("dam_break_front.gp",
                    {{"csvfile", (dir / "observables.csv").string()},
                     {"outfile", (dir / "front.png").string()},
                     {"ttl", opt.model + ", " + opt.integrator}},
                    err))
      out << "plot: " << (dir / "front.png").string() << "\n";
  }
}

namespace {

// Runs plots/SCRIPT with gnuplot, defining `vars` (name, value) as gnuplot strings. Values go
// inside gnuplot single quotes inside a shell double-quoted argument: single quotes are
// doubled, characters the shell would expand are dropped.
bool run_gnuplot(const std::string& script,
                 const std::vector<std::pair<std::string, std::string>>& vars, std::ostream& err) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    err << "gnuplot not found: plots skipped\n";
    return false;
  }
  std::ostringstream cmd;
  cmd << "gnuplot -e \"";
  for (const auto& [name, value] : vars) {
    std::string quoted;
    for (char ch : value) {
      if (ch == '"' || ch == '$' || ch == '`' || ch == '\\') continue;
      if (ch == '\'') quoted += '\'';
      quoted += ch;
    }
    cmd << name << "='" << quoted << "'; ";
  }
  cmd << "\" '" << STIFFBENCH_SOURCE_DIR << "/plots/" << script << "'";
  if (std::system(cmd.str().c_str()) != 0) {
    err << "gnuplot failed: " << cmd.str() << "\n";
    return false;
  }
  return true;
}

}  // namespace

bool plot_convergence(const std::string& csv, const std::string& png, const std::string& title,
                      const std::vector<std::string>& integrators, bool local, std::ostream& err) {
  return run_gnuplot(
      "convergence.gp",
      {{"csvfile", csv},
       {"outfile", png},
       {"methods", join(integrators, " ")},
       {"ttl", title},
       {"ycolumn", local ? "5" : "6"},
       {"ylab", local ? "local error (max-norm)" : "global error at t_end (max-norm)"}},
      err);
}

bool plot_work_precision(const std::string& csv, const std::string& png, const std::string& title,
                         const std::vector<std::string>& integrators, std::ostream& err) {
  return run_gnuplot(
      "work_precision.gp",
      {{"csvfile", csv}, {"outfile", png}, {"methods", join(integrators, " ")}, {"ttl", title}},
      err);
}

namespace {

struct SuiteItem {
  std::string name;
  std::string title;
  ConvergenceSpec spec;
  bool local = false;
};

std::vector<SuiteItem> default_suite(bool quick) {
  // The hand-written methods (the references are adaptive or have no fixed order: they appear
  // in the work-precision studies).
  std::vector<std::string> all, general;  // general: methods for first-order systems
  for (const auto& e : integrator_registry().entries()) {
    if (e.info.family == Family::reference) continue;
    all.push_back(e.info.name);
    if (!e.info.requires_.mechanical) general.push_back(e.info.name);
  }
  const int levels = quick ? 4 : 6;
  auto spec = [&](std::string model, std::vector<std::string> integ, double t_end, double h,
                  std::vector<std::string> params = {}, std::string reference = "auto") {
    ConvergenceSpec s;
    s.model = std::move(model);
    s.integrators = std::move(integ);
    s.t_end = t_end;
    s.h = h;
    s.levels = levels;
    s.params = Params::from_assignments(params);
    s.reference = std::move(reference);
    return s;
  };
  return {
      {"harmonic_oscillator", "Undamped harmonic oscillator (k = m = 1), t_end = 10",
       spec("harmonic_oscillator", all, 10.0, 0.1), false},
      {"harmonic_oscillator_local", "Local error, undamped harmonic oscillator",
       spec("harmonic_oscillator", all, 10.0, 0.1), true},
      // t_end = 5 is not a period: after exactly one period of this reversible orbit the
      // first-order errors of symplectic Euler cancel and it would show order 2.
      {"kepler_e05", "Kepler orbit, e = 0.5, t_end = 5 (exact via Kepler's equation)",
       spec("kepler", all, 5.0, 0.02, {"e=0.5"}), false},
      {"pendulum", "Nonlinear pendulum, θ0 = 1, t_end = 10 (reference rk4)",
       spec("pendulum", all, 10.0, 0.1, {}, "rk4"), false},
      {"prothero_robinson_l50",
       "Prothero-Robinson, λ = -50: explicit methods unstable for h|λ| beyond their limit",
       spec("prothero_robinson", general, 10.0, 0.1, {"lambda=-50"}), false},
      {"prothero_robinson_stiff",
       "Prothero-Robinson, λ = -1e6 (h|λ| up to 1e5): explicit methods unstable, L-stable "
       "methods track φ",
       spec("prothero_robinson", general, 10.0, 0.1, {"lambda=-1e6"}), false},
  };
}

}  // namespace

void cmd_report(const ReportOptions& opt, std::ostream& out, std::ostream& err) {
  namespace fs = std::filesystem;
  const auto suite = default_suite(opt.quick);
  std::ostringstream md;
  md << "# stiffbench report\n\n";
  md << "stiffbench " << STIFFBENCH_VERSION << ", revision " << git_revision() << ", "
     << (opt.quick ? "quick" : "full") << " suite. Each section links its full-precision CSV, "
     << "Markdown table and JSON metadata (spec, versions, compiler, flags, date).\n\n";
  md << "Errors are max-norms against the exact solution or the named reference; 'observed order' "
        "is "
        "log(e_k/e_{k+1})/log(h_k/h_{k+1}) between consecutive step sizes.\n\n";
  for (std::size_t i = 0; i < suite.size(); ++i) {
    const SuiteItem& item = suite[i];
    err << "== [" << i + 1 << "/" << suite.size() << "] " << item.name << "\n";
    const ConvergenceResult res =
        item.local ? run_local_error(item.spec, &err) : run_convergence(item.spec, &err);
    const std::string name = item.local ? "local_error" : "convergence";
    const fs::path dir = fs::path(opt.out_dir) / item.name;
    write_convergence_outputs(dir.string(), name, item.spec, res, item.local);
    const bool plotted =
        plot_convergence((dir / (name + ".csv")).string(), (dir / (name + ".png")).string(),
                         item.title, item.spec.integrators, item.local, err);
    md << "## " << item.title << "\n\n";
    md << "[" << name << ".csv](" << item.name << "/" << name << ".csv) · [" << name << ".md]("
       << item.name << "/" << name << ".md) · [" << name << ".json](" << item.name << "/" << name
       << ".json)\n\n";
    if (plotted) md << "![" << item.title << "](" << item.name << "/" << name << ".png)\n\n";
    md << "Reference: " << res.reference_description << ".\n\n";
    Table summary{{"integrator", item.local ? "expected slope" : "order", "last observed order",
                   "status of finest run"},
                  {}};
    for (const auto& integ : item.spec.integrators) {
      const auto last = last_observed_order(res.rows, integ);
      std::string status;
      int order = 0;
      for (const auto& r : res.rows)
        if (r.integrator == integ) {
          status = to_string(r.stats.status);
          order = r.order + (item.local ? 1 : 0);
        }
      summary.rows.push_back(
          {integ, std::to_string(order), last ? format_fixed(*last) : "-", status});
    }
    md << summary.to_markdown() << "\n";
  }
  // Work-precision: hand-written implicit methods against the library references.
  struct WpItem {
    std::string name, title;
    WorkPrecisionSpec spec;
  };
  std::vector<WpItem> wp_items;
  {
    WorkPrecisionSpec w;
    w.model = "hires";
    w.integrators = {"cvode_bdf", "arkode_dirk", "gsl_msbdf",  "gsl_bsimp",
                     "sdirk3",    "bdf2",        "rosenbrock2"};
    w.levels = opt.quick ? 3 : 4;
    w.tol_levels = opt.quick ? 4 : 7;
    w.repeats = opt.quick ? 1 : 3;
    wp_items.push_back(
        {"hires_work_precision", "HIRES (t_end = 321.8122): work against precision", w});
  }
  for (std::size_t i = 0; i < wp_items.size(); ++i) {
    const WpItem& item = wp_items[i];
    err << "== [work-precision " << i + 1 << "/" << wp_items.size() << "] " << item.name << "\n";
    const WorkPrecisionResult res = run_work_precision(item.spec, &err);
    const fs::path dir = fs::path(opt.out_dir) / item.name;
    write_work_precision_outputs(dir.string(), item.spec, res);
    const bool plotted = plot_work_precision((dir / "work_precision.csv").string(),
                                             (dir / "work_precision.png").string(), item.title,
                                             item.spec.integrators, err);
    md << "## " << item.title << "\n\n";
    md << "[work_precision.csv](" << item.name << "/work_precision.csv) · [work_precision.md]("
       << item.name << "/work_precision.md) · [work_precision.json](" << item.name
       << "/work_precision.json)\n\n";
    if (plotted) md << "![" << item.title << "](" << item.name << "/work_precision.png)\n\n";
    md << "Reference: " << res.reference_description
       << ". Fixed-step methods over h, references over "
       << "rtol (atol = " << format_full(item.spec.atol_factor) << "·rtol).\n\n";
    Table summary{{"integrator", "settings", "best error", "f_evals at best", "status"}, {}};
    for (const auto& name : item.spec.integrators) {
      int n = 0;
      double best = std::numeric_limits<double>::infinity();
      long fe = 0;
      std::string status = "ok";
      for (const auto& r : res.rows) {
        if (r.integrator != name) continue;
        ++n;
        if (r.stats.status != Status::ok)
          status = to_string(r.stats.status);
        else if (r.error < best) {
          best = r.error;
          fe = r.stats.f_evals;
        }
      }
      summary.rows.push_back({name, std::to_string(n),
                              std::isfinite(best) ? format_short(best) : "-", std::to_string(fe),
                              status});
    }
    md << summary.to_markdown() << "\n";
  }
  write_file_atomic(fs::path(opt.out_dir) / "REPORT.md", md.str());
  out << "wrote " << (fs::path(opt.out_dir) / "REPORT.md").string() << "\n";
}

}  // namespace stiffbench

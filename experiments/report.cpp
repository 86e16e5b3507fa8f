// `stiffbench report`: the default suite, one folder per study and DIR/REPORT.md linking every
// table and plot.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <ostream>
#include <sstream>

#include "experiments/build_info.hpp"
#include "experiments/catalog.hpp"
#include "experiments/commands.hpp"
#include "experiments/energy.hpp"
#include "experiments/plotting.hpp"
#include "experiments/region.hpp"
#include "experiments/stability.hpp"
#include "experiments/work_precision.hpp"

namespace stiffbench {

namespace {

struct SuiteItem {
  std::string name;
  std::string title;
  ConvergenceSpec spec;
  bool local = false;
  std::string note;  // one sentence: what the section shows and what to look at
};

std::vector<SuiteItem> default_suite(bool quick) {
  // The hand-written methods (the references are adaptive or have no fixed order: they appear
  // in the work-precision studies).
  std::vector<std::string> all, general;  // general: methods for first-order systems
  for (const auto& e : integrator_registry().entries()) {
    // rattle needs a constrained system, xpbd/projective_dynamics a spring network: the
    // suite's models are neither.
    if (e.info.family == Family::reference || e.info.requires_.constraints) continue;
    if (e.info.requires_.spring_network) continue;
    if (e.info.requires_.grid_fluid) continue;  // stable_fluids: fluid_2d only
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
       spec("harmonic_oscillator", all, 10.0, 0.1), false,
       "Global error against h: each method's line should run parallel to its dashed "
       "expected-slope line once h is small enough (the observed order equals the order)."},
      {"harmonic_oscillator_local", "Local error, undamped harmonic oscillator",
       spec("harmonic_oscillator", all, 10.0, 0.1), true,
       "Error of one step from the initial state: the slope is the order plus one, the "
       "check that a method's tableau and start-up step are what they claim."},
      // t_end = 5 is not a period: after exactly one period of this reversible orbit the
      // first-order errors of symplectic Euler cancel and it would show order 2.
      {"kepler_e05", "Kepler orbit, e = 0.5, t_end = 5 (exact via Kepler's equation)",
       spec("kepler", all, 5.0, 0.02, {"e=0.5"}), false,
       "A nonlinear orbit with a fast pericentre passage: the coarsest steps are "
       "pre-asymptotic, look at the observed orders of the finest pairs."},
      {"pendulum", "Nonlinear pendulum, θ0 = 1, t_end = 10 (reference rk4)",
       spec("pendulum", all, 10.0, 0.1, {}, "rk4"), false,
       "Orders on a nonlinear problem without an exact solution, against an rk4 run at a 16 "
       "times finer step."},
      {"prothero_robinson_l50",
       "Prothero-Robinson, λ = -50: explicit methods unstable for h|λ| beyond their limit",
       spec("prothero_robinson", general, 10.0, 0.1, {"lambda=-50"}), false,
       "Explicit methods have no finite error until h|λ| is inside their stability interval; "
       "implicit ones converge from the coarsest step."},
      {"prothero_robinson_stiff",
       "Prothero-Robinson, λ = -1e6 (h|λ| up to 1e5): explicit methods unstable, L-stable "
       "methods track φ",
       spec("prothero_robinson", general, 10.0, 0.1, {"lambda=-1e6"}), false,
       "Order reduction on a very stiff problem: look for implicit methods whose observed "
       "order falls below their classical order (stage order matters here)."},
  };
}

void stability_sections(const ReportOptions& opt, std::ostringstream& md, std::ostream& err) {
  namespace fs = std::filesystem;
  struct Item {
    std::string name, title, note;
    StabilitySpec spec;
  };
  std::vector<Item> items;
  {
    StabilitySpec s;
    s.model = "spring_chain";
    s.integrators = {"euler",           "heun",           "kutta3", "rk4", "symplectic_euler",
                     "velocity_verlet", "backward_euler", "sdirk3", "bdf2"};
    parse_sweep(opt.quick ? "k=1:100:3" : "k=1:10000:5", s.sweep_param, s.sweep_values);
    items.push_back({"spring_chain_stability",
                     "Stability limit against spring stiffness: chain of 10 masses, fixed ends",
                     "Measured largest stable step (points) against linear theory from the "
                     "exact spectrum (dashed): the lines coincide and fall as k^(-1/2); Euler "
                     "and Heun have no stable step on undamped springs, the A-stable methods are "
                     "stable at every step tried.",
                     s});
  }
  if (!opt.quick) {
    StabilitySpec s;
    s.model = "sph_drop_2d";
    s.params = Params::from_assignments({"n=10"});
    s.integrators = {"symplectic_euler", "velocity_verlet"};
    parse_sweep("k=1000:100000:3", s.sweep_param, s.sweep_values);
    items.push_back({"sph_drop_stability",
                     "Stability limit against EOS stiffness: 2D SPH drop (n = 10)",
                     "The measured limit scales as k^(-1/2) like the sound speed; the "
                     "prediction uses the model's estimate c/h of the fastest rate, so the "
                     "ratio (measured/predicted) says how conservative that estimate is.",
                     s});
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Item& item = items[i];
    err << "== [stability " << i + 1 << "/" << items.size() << "] " << item.name << "\n";
    const StabilityResult res = run_stability(item.spec, &err);
    const fs::path dir = fs::path(opt.out_dir) / item.name;
    write_stability_outputs(dir, item.spec, res);
    const bool plotted = plot_stability(dir / "stability.csv", item.title, {opt.svg}, err);
    md << "## " << item.title << "\n\n";
    md << "[stability.csv](" << item.name << "/stability.csv) · [stability.md](" << item.name
       << "/stability.md) · [stability.json](" << item.name << "/stability.json)\n\n";
    if (plotted) md << "![" << item.title << "](" << item.name << "/stability.png)\n\n";
    md << item.note << " Spectrum: " << res.spectrum_source << ".\n\n";
    Table summary{{"integrator", "statuses", "h_max/predicted (range)", "slope of log h_max",
                   "predicted slope"},
                  {}};
    for (const auto& name : item.spec.integrators) {
      std::string statuses;
      double rmin = 1e300, rmax = -1e300;
      for (const auto& r : res.rows) {
        if (r.integrator != name) continue;
        if (statuses.find(r.status) == std::string::npos)
          statuses += (statuses.empty() ? "" : ", ") + r.status;
        if (r.status == "ok" && r.h_measured && r.h_predicted && *r.h_predicted > 0) {
          rmin = std::min(rmin, *r.h_measured / *r.h_predicted);
          rmax = std::max(rmax, *r.h_measured / *r.h_predicted);
        }
      }
      std::string slope = "-", pslope = "-";
      for (const auto& f : res.fits)
        if (f.integrator == name) {
          if (f.measured_slope) slope = format_fixed(*f.measured_slope, 3);
          if (f.predicted_slope) pslope = format_fixed(*f.predicted_slope, 3);
        }
      summary.rows.push_back(
          {name, statuses,
           rmin <= rmax ? format_fixed(rmin, 4) + " - " + format_fixed(rmax, 4) : "-", slope,
           pslope});
    }
    md << summary.to_markdown() << "\n";
  }
}

void energy_sections(const ReportOptions& opt, std::ostringstream& md, std::ostream& err) {
  namespace fs = std::filesystem;
  struct Item {
    std::string name, title, note;
    EnergySpec spec;
  };
  std::vector<Item> items;
  {
    EnergySpec s;
    s.model = "kepler";
    s.params = Params::from_assignments({"e=0.5"});
    s.integrators = {"euler", "rk4", "velocity_verlet", "symplectic_euler"};
    s.h = 0.01;
    const int orbits = opt.quick ? 100 : 1000;
    s.t_end = orbits * 2.0 * std::numbers::pi;
    items.push_back(
        {"kepler_energy",
         "Energy drift: Kepler orbit, e = 0.5, h = 0.01, " + std::to_string(orbits) + " orbits",
         "Relative energy error (largest since the previous sample, so pericentre "
         "peaks are kept): the symplectic methods oscillate in a bounded band "
         "(growth ~1), rk4 drifts linearly (growth ~10), explicit Euler spirals "
         "out.",
         s});
  }
  {
    EnergySpec s;
    s.model = "cloth";
    s.params =
        Params::from_assignments({"n=8", "gravity=0", "prestretch=1.1", "perturbation=0.01"});
    s.integrators = {"symplectic_euler", "velocity_verlet", "rk4", "backward_euler"};
    if (!opt.quick) s.integrators.push_back("sdirk3");
    s.h = 0.01;
    s.t_end = opt.quick ? 10.0 : 20.0;
    items.push_back({"cloth_energy",
                     "Energy drift: undamped cloth 8 x 8, prestretched 10%, no gravity, h = 0.01",
                     "A stiff conservative network: symplectic methods keep the spring energy "
                     "in a band, rk4 loses it slowly, and the implicit methods' numerical "
                     "damping removes most of it (look at the implicit panel's level, not its "
                     "shape).",
                     s});
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Item& item = items[i];
    err << "== [energy " << i + 1 << "/" << items.size() << "] " << item.name << "\n";
    const EnergyResult res = run_energy(item.spec, &err);
    const fs::path dir = fs::path(opt.out_dir) / item.name;
    const bool plotted = write_energy_outputs(dir, item.spec, res, {opt.svg}, err);
    md << "## " << item.title << "\n\n";
    md << "[energy.csv](" << item.name << "/energy.csv) · [energy_summary.csv](" << item.name
       << "/energy_summary.csv) · [energy.md](" << item.name << "/energy.md) · [energy.json]("
       << item.name << "/energy.json)\n\n";
    if (plotted) md << "![" << item.title << "](" << item.name << "/energy.png)\n\n";
    md << item.note << "\n\n" << energy_markdown_table(res).to_markdown() << "\n";
  }
}

void region_section(const ReportOptions& opt, std::ostringstream& md, std::ostream& err) {
  namespace fs = std::filesystem;
  err << "== [regions] stability regions of every hand-written method\n";
  RegionSpec spec;  // every integrator with stability data, box fitted to them
  spec.resolution = opt.quick ? 200 : 400;
  const RegionResult res = run_region(spec);
  const fs::path dir = fs::path(opt.out_dir) / "stability_regions";
  write_region_outputs(dir, spec, res);
  const std::string title = "Stability regions |R(z)| = 1 of the hand-written methods";
  const bool plotted = plot_region(dir / "region.csv", title, {opt.svg}, err);
  md << "## " << title << "\n\n";
  md << "[region.csv](stability_regions/region.csv) · [region_limits.csv]"
        "(stability_regions/region_limits.csv) · [region.md](stability_regions/region.md) · "
        "[region.json](stability_regions/region.json)\n\n";
  if (plotted) md << "![" << title << "](stability_regions/region.png)\n\n";
  md << "Computed from each method's coefficients (R(z) = 1 + z bᵀ(I − zA)⁻¹1, BDF2's boundary "
        "locus), not from runs: explicit methods are stable inside their closed curves, "
        "implicit ones outside theirs; the real- and imaginary-axis limits below are what "
        "`stability` compares its measurements with (oscillator hω for the splitting "
        "methods, which have no scalar R(z)).\n\n";
  md << region_limits_markdown_table(res).to_markdown() << "\n";
}

}  // namespace

nlohmann::json report_spec(const ReportOptions& opt) {
  return {{"suite", opt.quick ? "quick" : "full"}};
}

void cmd_report(const ReportOptions& opt, std::ostream& out, std::ostream& err) {
  namespace fs = std::filesystem;
  require_output_dir(opt.out_dir);
  // Output safety: DIR/report.json records the suite; a folder holding a report of the other
  // suite is refused unless --force. Plot formats (--svg) are not part of it, as for the
  // studies. Written before the suite runs, so an interrupted report is identified too.
  const nlohmann::json spec = report_spec(opt);
  check_existing_results(opt.out_dir, "report.json", {"REPORT.md"}, spec, force_output(), &err);
  write_file_atomic(fs::path(opt.out_dir) / "report.json",
                    run_metadata("report", spec).dump(2) + "\n");
  const auto suite = default_suite(opt.quick);
  const PlotOptions plot_opt{opt.svg};
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
        plot_convergence(dir / (name + ".csv"), item.title, item.local, plot_opt, err);
    md << "## " << item.title << "\n\n";
    md << "[" << name << ".csv](" << item.name << "/" << name << ".csv) · [" << name << ".md]("
       << item.name << "/" << name << ".md) · [" << name << ".json](" << item.name << "/" << name
       << ".json)\n\n";
    if (plotted) md << "![" << item.title << "](" << item.name << "/" << name << ".png)\n\n";
    md << item.note << " Reference: " << res.reference_description << ".\n\n";
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
  energy_sections(opt, md, err);
  region_section(opt, md, err);
  stability_sections(opt, md, err);
  // Work-precision: hand-written implicit methods against the library references.
  struct WpItem {
    std::string name, title;
    WorkPrecisionSpec spec;
    std::string note;
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
        {"hires_work_precision", "HIRES (t_end = 321.8122): work against precision", w,
         "Error against f evaluations and wall time on a stiff chemical system: the cheapest "
         "method for a given error is the lowest line; fixed-step methods and tolerance "
         "ladders share the axes."});
  }
  {
    // Cloth: the mechanical model the testbed is about; fixed-step symplectic and implicit
    // methods against CVODE (reference: cvode_bdf at rtol 1e-14).
    WorkPrecisionSpec w;
    w.model = "cloth";
    w.params = Params::from_assignments({"n=8", "m=8"});
    w.t_end = opt.quick ? 0.5 : 1.0;
    w.h = 0.01;
    w.integrators = {"symplectic_euler", "velocity_verlet", "rk4",
                     "baraff_witkin",    "sdirk3",          "cvode_bdf"};
    if (!opt.quick) w.integrators.insert(w.integrators.begin() + 4, "backward_euler");
    w.levels = opt.quick ? 3 : 5;
    w.tol_levels = opt.quick ? 3 : 5;
    w.repeats = opt.quick ? 1 : 3;
    wp_items.push_back({"cloth_work_precision",
                        "Cloth 8 x 8 (pinned corners, gravity): work against precision", w,
                        "The mechanical model of graphics: cheap explicit steps against "
                        "implicit solves and CVODE; look at which family reaches a given error "
                        "with the least work, and at how slowly the first-order implicit "
                        "Euler variants converge."});
  }
  for (std::size_t i = 0; i < wp_items.size(); ++i) {
    const WpItem& item = wp_items[i];
    err << "== [work-precision " << i + 1 << "/" << wp_items.size() << "] " << item.name << "\n";
    const WorkPrecisionResult res = run_work_precision(item.spec, &err);
    const fs::path dir = fs::path(opt.out_dir) / item.name;
    write_work_precision_outputs(dir.string(), item.spec, res);
    const bool plotted = plot_work_precision(dir / "work_precision.csv", item.title, plot_opt, err);
    md << "## " << item.title << "\n\n";
    md << "[work_precision.csv](" << item.name << "/work_precision.csv) · [work_precision.md]("
       << item.name << "/work_precision.md) · [work_precision.json](" << item.name
       << "/work_precision.json)\n\n";
    if (plotted) md << "![" << item.title << "](" << item.name << "/work_precision.png)\n\n";
    md << item.note << " Reference: " << res.reference_description
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

// The stiffbench command line (experiments/cli_main.hpp). Exit codes: 0 success, 2 bad input
// (one message on stderr naming what is wrong), 3 a row ended with status error or timeout,
// 128 + signal when interrupted by SIGINT/SIGTERM, 1 anything else.
#include "experiments/cli_main.hpp"

#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <limits>

#include "core/driver.hpp"
#include "core/run_control.hpp"
#include "experiments/catalog.hpp"
#include "experiments/cli.hpp"
#include "experiments/commands.hpp"
#include "experiments/sweep.hpp"
#include "experiments/work_precision.hpp"

namespace stiffbench {

namespace {

void add_study_flags(CLI::App* cmd, ConvergenceSpec& spec, std::string& integrators,
                     std::vector<std::string>& params, std::string& out_dir) {
  cmd->add_option("--model", spec.model, "model name (see `stiffbench list models`)")->required();
  cmd->add_option("--integrators", integrators, "comma-separated integrator names")->required();
  cmd->add_option("--param", params, "model/integrator parameter key=value (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--t-end", spec.t_end, "final time")->required();
  cmd->add_option("--h", spec.h,
                  "coarsest step size (default: the model's suggested step, where it has one)");
  cmd->add_option("--levels", spec.levels, "number of step sizes (>= 2)")->capture_default_str();
  cmd->add_option("--refine", spec.refine, "ratio between consecutive step sizes (> 1)")
      ->capture_default_str();
  cmd->add_option("--reference", spec.reference,
                  "exact | METHOD: an adaptive integrator (cvode_bdf, cvode_adams, arkode_*, "
                  "gsl_*) runs at --reference-rtol/--reference-atol and stops exactly at the "
                  "reference times; a fixed-step one (e.g. rk4) runs at (finest h)/16. Default: "
                  "exact where the model has one; a model without one needs --reference. A "
                  "non-exact reference is cached in OUT/reference/<hash>.csv and reused by a "
                  "run of the same build with the same model, parameters, reference and times")
      ->capture_default_str();
  cmd->add_option("--reference-rtol", spec.reference_rtol,
                  "relative tolerance of an adaptive --reference (default 1e-12)");
  cmd->add_option("--reference-atol", spec.reference_atol,
                  "absolute tolerance of an adaptive --reference (default rtol/100)");
  cmd->add_option("--out", out_dir, "output directory")->capture_default_str();
}

PlotOptions g_plot;  // --svg of convergence, local-error and work-precision

// The first SIGINT or SIGTERM asks the runs to stop at their next poll (core/run_control.hpp):
// the current row is abandoned, the files already written stay complete (each is written under a
// temporary name and renamed; `run` appends whole lines), and cli_main returns 128 + signal. The
// action is reset to the default on delivery (SA_RESETHAND), so a second signal ends the process
// at once. Installed for the duration of cli_main only; the previous handlers are restored.
extern "C" void on_interrupt_signal(int sig) { request_interrupt(sig); }

class InterruptHandlers {
 public:
  InterruptHandlers() {
    clear_interrupt();
    struct sigaction sa {};
    sa.sa_handler = on_interrupt_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    for (int i = 0; i < 2; ++i) sigaction(kSignals[i], &sa, &old_[i]);
  }
  ~InterruptHandlers() {
    for (int i = 0; i < 2; ++i) sigaction(kSignals[i], &old_[i], nullptr);
    clear_interrupt();
  }
  InterruptHandlers(const InterruptHandlers&) = delete;
  InterruptHandlers& operator=(const InterruptHandlers&) = delete;

 private:
  static constexpr int kSignals[2] = {SIGINT, SIGTERM};
  struct sigaction old_[2];
};

int interrupted_exit(int sig) {
  remove_created_output_dirs();  // only folders this run created and left empty
  std::cerr << "stiffbench: interrupted by " << (sig == SIGTERM ? "SIGTERM" : "SIGINT")
            << ": the run in progress was abandoned; files already written are complete\n";
  return 128 + (sig > 0 ? sig : SIGINT);
}

}  // namespace

int cli_main(int argc, char** argv) {
  set_command_line(argc, argv);
  const struct ForgetCommandLine {
    ~ForgetCommandLine() { clear_command_line(); }
  } forget;
  CLI::App app{
      "stiffbench: a testbed comparing time integrators on stiff ODEs from physically based "
      "simulation.\nExit codes: 0 success, 2 bad input, 3 a row ended with status error or timeout "
      "(its table is written), 130/143 interrupted by SIGINT/SIGTERM, 1 other errors."};
  app.require_subcommand(1);

  std::string list_what;
  auto* list = app.add_subcommand("list", "list models, integrators or experiments");
  list->add_option("what", list_what, "models | integrators | experiments (default: all)")
      ->check(CLI::IsMember({"models", "integrators", "experiments"}));

  std::string describe_name;
  auto* describe = app.add_subcommand(
      "describe", "parameters, defaults and properties of a model, integrator or experiment");
  describe->add_option("name", describe_name, "model, integrator or experiment name")->required();

  SolveOptions solve_opt;
  std::vector<std::string> solve_params;
  auto* solve =
      app.add_subcommand("solve",
                         "one run (fixed step with --h, else the model's suggested step or "
                         "adaptive): final state, invariants, observables, statistics; --frames "
                         "writes particle frames");
  solve->add_option("--model", solve_opt.model, "model name")->required();
  solve->add_option("--integrator", solve_opt.integrator, "integrator name")->required();
  solve->add_option("--h", solve_opt.h,
                    "step size (the run takes N = round(T/h) steps of T/N); omit for the adaptive "
                    "mode of a reference integrator or the model's suggested step");
  solve->add_option("--t-end", solve_opt.t_end,
                    "final time (default: the model's literature end time)");
  solve->add_option("--outputs", solve_opt.outputs, "number of output intervals in the trajectory")
      ->capture_default_str();
  solve->add_option("--param", solve_params, "model/integrator parameter key=value (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  solve->add_option("--out", solve_opt.out_csv,
                    "trajectory CSV file (columns t,y0,y1,...; no spec is recorded beside it, "
                    "so an existing file is refused unless --force); with --frames, the output "
                    "directory (its solve.json records the spec)");
  solve->add_option("--frames", solve_opt.frames,
                    "write N+1 equally spaced frames into the --out directory: VTK particle "
                    "frames (frame_NNNN.vtu, frames.pvd) for particle models, trajectory.csv "
                    "otherwise, and observables.csv");
  std::string solve_times;
  solve->add_option("--times", solve_times,
                    "output times t1,t2,... (increasing, in (t0, t_end]; without --t-end the run "
                    "ends at the last) instead of --outputs: adaptive integrators stop exactly at "
                    "each (no interpolation); fixed-step runs report the nearest step and print "
                    "and write its actual t. --out gets one row per time");
  solve->add_option("--log-outputs", solve_opt.log_outputs,
                    "N output times log-spaced in t - t0 from --log-first to t_end: t_k = t0 + "
                    "(t1 - t0)*((t_end - t0)/(t1 - t0))^((k-1)/(N-1)); default t1 = t0 + "
                    "(t_end - t0)*10^-(N-1), one per decade; same stops as --times");
  solve->add_option("--log-first", solve_opt.log_first,
                    "first time of --log-outputs (default: N-1 decades before t_end)");
  solve
      ->add_option("--frame-format", solve_opt.frame_format,
                   "particle frame files: vtu (VTK XML + frames.pvd) or vtk (legacy); a CSV "
                   "copy of each frame is always written for gnuplot")
      ->check(CLI::IsMember({"vtu", "vtk"}))
      ->capture_default_str();

  ConvergenceSpec conv;
  conv.h = std::numeric_limits<double>::quiet_NaN();
  std::string conv_integrators, conv_out = "results";
  std::vector<std::string> conv_params;
  auto* convergence = app.add_subcommand(
      "convergence",
      "global error at t_end against h = H/refine^k; writes convergence.{csv,md,json}");
  add_study_flags(convergence, conv, conv_integrators, conv_params, conv_out);
  convergence->add_flag("--svg", g_plot.svg, "also write the plot as SVG");

  ConvergenceSpec local;
  std::string local_integrators, local_out = "results";
  std::vector<std::string> local_params;
  auto* local_error = app.add_subcommand(
      "local-error",
      "error of one step from the initial state against h; writes local_error.{csv,md,json}");
  local.t_end = 1.0;
  local.h = std::numeric_limits<double>::quiet_NaN();
  add_study_flags(local_error, local, local_integrators, local_params, local_out);
  local_error->get_option("--t-end")->required(false)->description(
      "unused by the local study's error; kept for symmetry");
  local_error->add_flag("--svg", g_plot.svg, "also write the plot as SVG");

  WorkPrecisionSpec wp;
  std::string wp_integrators, wp_out = "results";
  std::vector<std::string> wp_params;
  auto* work_precision = app.add_subcommand(
      "work-precision",
      "error against work: fixed-step methods over an h ladder, references over a tolerance "
      "ladder; writes work_precision.{csv,md,json}");
  work_precision->add_option("--model", wp.model, "model name")->required();
  work_precision->add_option("--integrators", wp_integrators, "comma-separated integrator names")
      ->required();
  work_precision
      ->add_option("--param", wp_params, "model/integrator parameter key=value (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  work_precision->add_option("--t-end", wp.t_end,
                             "final time (default: the model's literature end time)");
  work_precision->add_option("--h", wp.h,
                             "coarsest step of fixed-step methods (default: the model's suggested "
                             "step, else (t_end - t0)/16000)");
  work_precision->add_option("--levels", wp.levels, "number of step sizes")->capture_default_str();
  work_precision->add_option("--refine", wp.refine, "ratio between step sizes")
      ->capture_default_str();
  work_precision
      ->add_option("--tol-levels", wp.tol_levels, "number of tolerances (factor 10 apart)")
      ->capture_default_str();
  work_precision->add_option("--rtol-max", wp.rtol_max, "loosest relative tolerance")
      ->capture_default_str();
  work_precision->add_option("--atol-factor", wp.atol_factor, "atol = atol_factor * rtol")
      ->capture_default_str();
  work_precision->add_option("--repeats", wp.repeats, "runs per setting; wall time is the minimum")
      ->capture_default_str();
  work_precision
      ->add_option("--reference", wp.reference,
                   "exact | METHOD; default: exact where available, else cvode_bdf")
      ->capture_default_str();
  work_precision
      ->add_option("--reference-rtol", wp.reference_rtol, "rtol of an adaptive reference run")
      ->capture_default_str();
  work_precision
      ->add_option("--reference-atol", wp.reference_atol, "atol of an adaptive reference run")
      ->capture_default_str();
  work_precision->add_option("--out", wp_out, "output directory")->capture_default_str();
  work_precision->add_flag("--svg", g_plot.svg, "also write the plot as SVG");

  ReportOptions report_opt;
  auto* report = app.add_subcommand("report", "run the default suite and write DIR/REPORT.md");
  report->add_option("--out", report_opt.out_dir, "output directory")->capture_default_str();
  report->add_flag("--quick", report_opt.quick, "fewer step sizes (a smoke run)");
  report->add_flag("--svg", report_opt.svg, "also write each plot as SVG");

  add_stability_command(app);
  add_region_command(app);
  add_energy_command(app);
  add_plot_command(app);
  add_run_commands(app);

  // --max-memory on every command that builds models (checked by make_setup before anything is
  // allocated; README "Sizes and memory").
  for (const char* name : {"solve", "convergence", "local-error", "work-precision", "stability",
                           "energy", "run", "report"}) {
    if (auto* sub = app.get_subcommand(name)) {
      sub->add_option_function<std::string>(
          "--max-memory", [](const std::string& v) { set_memory_limit(parse_memory_size(v)); },
          "refuse a run whose estimated memory exceeds this (bytes, or with K/M/G/T; default: "
          "the memory available now)");
    }
  }
  // --max-wall on every command that runs integrators (core/run_control.hpp; README "Faults
  // and exit codes"); reset when cli_main returns.
  const struct ForgetWallLimit {
    ~ForgetWallLimit() { set_wall_limit(0); }
  } forget_wall_limit;
  for (const char* name : {"solve", "convergence", "local-error", "work-precision", "stability",
                           "energy", "run", "report"}) {
    if (auto* sub = app.get_subcommand(name)) {
      sub->add_option_function<double>(
          "--max-wall", [](double s) { set_wall_limit(s); },
          "wall-clock limit of each row in seconds (a run; a stability row's whole bisection): a "
          "row over it ends with status timeout and the study goes on (default 0: none)");
    }
  }
  // --force on every command that writes results (README "Existing results"): replace results
  // of a different spec in --out (check_existing_results); reset when cli_main returns.
  const struct ForgetForce {
    ForgetForce() { set_force_output(false); }
    ~ForgetForce() { set_force_output(false); }
  } forget_force;
  for (const char* name : {"solve", "convergence", "local-error", "work-precision", "stability",
                           "energy", "region", "run", "merge", "report"}) {
    if (auto* sub = app.get_subcommand(name)) {
      sub->add_flag_function(
          "--force", [](std::int64_t) { set_force_output(true); },
          "replace results of a different spec in --out (default: refuse them)");
    }
  }
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    std::vector<std::string> names;
    for (const auto* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      names.push_back(sub->get_name());
      known = known || sub->get_name() == argv[1];
    }
    if (!known) {
      std::cerr << "stiffbench: unknown command '" << argv[1] << "'" << did_you_mean(argv[1], names)
                << "; known: " << join(names) << "\n";
      return 2;
    }
  }
  // SIGINT/SIGTERM: the runs stop at their next poll, and the exit code is 128 + signal.
  const InterruptHandlers handlers;
  // Subcommands registered by add_*_command run inside parse() (their callbacks), so one try
  // covers parsing and running.
  try {
    app.parse(argc, argv);
    if (*list) cmd_list(list_what, std::cout);
    if (*describe) cmd_describe(describe_name, std::cout);
    if (*solve) {
      solve_opt.params = Params::from_assignments(solve_params);
      if (solve->count("--times")) solve_opt.times = parse_times(solve_times);
      cmd_solve(solve_opt, std::cout, std::cerr);
    }
    if (*convergence || *local_error) {
      const bool is_local = local_error->parsed();
      ConvergenceSpec& spec = is_local ? local : conv;
      spec.integrators =
          split_list(is_local ? local_integrators : conv_integrators, "--integrators");
      spec.params = Params::from_assignments(is_local ? local_params : conv_params);
      const std::string& dir = is_local ? local_out : conv_out;
      spec.cache_dir = dir;
      const std::string name = is_local ? "local_error" : "convergence";
      require_output_dir(dir);
      check_study_output(dir, name, spec.to_json(), force_output(), &std::cerr);
      const ConvergenceResult res =
          is_local ? run_local_error(spec, &std::cerr) : run_convergence(spec, &std::cerr);
      write_convergence_outputs(dir, name, spec, res, is_local);
      std::cout << (is_local ? local_error_table(res) : convergence_table(res)).to_markdown();
      std::cout << "\nwrote " << dir << "/" << name << ".{csv,md,json}\n";
      const std::filesystem::path csv = std::filesystem::path(dir) / (name + ".csv");
      if (plot_convergence(csv, (is_local ? "Local error: " : "Global error: ") + spec.model,
                           is_local, g_plot, std::cerr))
        std::cout << "plot: " << dir << "/" << name << ".png\n";
    }
    if (*work_precision) {
      wp.integrators = split_list(wp_integrators, "--integrators");
      wp.params = Params::from_assignments(wp_params);
      require_output_dir(wp_out);
      check_study_output(wp_out, "work_precision", wp.to_json(), force_output(), &std::cerr);
      const WorkPrecisionResult res = run_work_precision(wp, &std::cerr);
      write_work_precision_outputs(wp_out, wp, res);
      std::cout << work_precision_table(res).to_markdown();
      std::cout << "\nwrote " << wp_out << "/work_precision.{csv,md,json}\n";
      if (plot_work_precision(std::filesystem::path(wp_out) / "work_precision.csv",
                              "Work-precision: " + wp.model, g_plot, std::cerr))
        std::cout << "plot: " << wp_out << "/work_precision.png\n";
    }
    if (*report) cmd_report(report_opt, std::cout, std::cerr);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    remove_created_output_dirs();
    std::cerr << "stiffbench: " << e.what() << "\n";
    return 2;
  } catch (const BadInput& e) {
    // A refused run leaves no trace: output folders created for it are removed when empty.
    remove_created_output_dirs();
    std::cerr << "stiffbench: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "stiffbench: error: " << e.what() << "\n";
    return 1;
  } catch (const Interrupted& i) {
    return interrupted_exit(i.signal);
  }
  // A signal that arrived after the last run (while a table or plot was written): the results
  // are complete, but the exit code still says the command was interrupted.
  if (const int sig = interrupt_requested()) return interrupted_exit(sig);
  // A run that ended with status error (the model or the integrator threw mid-run) is a failed
  // row: its table was written, and the exit code says so (README).
  if (const long faults = fault_count(); faults > 0) {
    std::cerr << "stiffbench: " << faults << " run" << (faults == 1 ? "" : "s")
              << " ended with status error or timeout (see the status and message columns)\n";
    return kExitRowsFailed;
  }
  return 0;
}

}  // namespace stiffbench

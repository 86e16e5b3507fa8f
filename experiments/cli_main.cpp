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

namespace stiffbench {

namespace {

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

  ReportOptions report_opt;
  auto* report = app.add_subcommand(
      "report",
      "run a suite of spec files (default: the built-in suite, experiments/specs/report/) and "
      "write DIR/REPORT.md with one section per spec");
  report->add_option("suite", report_opt.suite,
                     "a folder of spec files (run in name order) or spec files, one section each "
                     "(default: the built-in suite)");
  report->add_option("--out", report_opt.out_dir, "output directory")->capture_default_str();
  report->add_flag("--quick", report_opt.quick,
                   "apply each spec's [quick] overrides (fewer step sizes: a smoke run)");
  report->add_flag("--svg", report_opt.svg, "also write each plot as SVG");

  add_study_commands(app);
  add_plot_command(app);
  add_run_commands(app);

  // --max-memory, --max-wall and --force on the commands that build models, run integrators and
  // write results (README "Sizes and memory", "Faults and exit codes", "Existing results").
  std::vector<std::string> builds_models = {"solve", "run", "report"}, writes = {"solve", "run",
                                                                            "merge", "report"};
  for (const auto& k : study_kinds()) {
    if (k.takes_model) builds_models.push_back(k.name);
    writes.push_back(k.name);
  }
  for (const auto& name : builds_models) {
    if (auto* sub = app.get_subcommand(name)) {
      sub->add_option_function<std::string>(
          "--max-memory", [](const std::string& v) { set_memory_limit(parse_memory_size(v)); },
          "refuse a run whose estimated memory exceeds this (bytes, or with K/M/G/T; default: "
          "the memory available now)");
    }
  }
  // --max-wall (core/run_control.hpp): reset when cli_main returns.
  const struct ForgetWallLimit {
    ~ForgetWallLimit() { set_wall_limit(0); }
  } forget_wall_limit;
  for (const auto& name : builds_models) {
    if (auto* sub = app.get_subcommand(name)) {
      sub->add_option_function<double>(
          "--max-wall", [](double s) { set_wall_limit(s); },
          "wall-clock limit of each row in seconds (a run; a stability row's whole bisection): a "
          "row over it ends with status timeout and the study goes on (default 0: none)");
    }
  }
  // --force: replace results of a different spec in --out (check_existing_results); reset when
  // cli_main returns.
  const struct ForgetForce {
    ForgetForce() { set_force_output(false); }
    ~ForgetForce() { set_force_output(false); }
  } forget_force;
  for (const auto& name : writes) {
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

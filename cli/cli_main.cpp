// The stiffbench command line (cli/cli_main.hpp). Exit codes: 0 success, 2 bad input
// (one message on stderr naming what is wrong), 3 a row ended with status error or timeout,
// 128 + signal when interrupted by SIGINT/SIGTERM, 1 anything else (compare: the runs differ).
#include "cli/cli_main.hpp"

#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>

#include "cli/cli.hpp"
#include "core/driver.hpp"
#include "core/run_control.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/commands/run.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"
#include "experiments/studies/audit.hpp"

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

// --max-memory, --max-wall and --force on the commands that build models, run integrators and
// write results (docs/common.md: sizes and memory, faults, existing results).
void add_run_limits(CLI::App& app) {
  std::vector<std::string> builds_models = {"solve", "run", "report", "profile"};
  std::vector<std::string> writes = {"solve", "run", "merge", "report", "profile"};
  for (const auto& k : study_kinds()) {
    if (k.takes_model) builds_models.push_back(k.name);
    writes.push_back(k.name);
  }
  for (const auto& name : builds_models) {
    if (auto* sub = app.get_subcommand(name))
      sub->add_option_function<std::string>(
          "--max-memory", [](const std::string& v) { set_memory_limit(parse_memory_size(v)); },
          "refuse a run whose estimated memory exceeds this (bytes, or with K/M/G/T; default: "
          "the memory available now)");
  }
  // Every command that computes rows: the studies without a model (region, analyze, audit)
  // too, where a row is one method's analysis.
  for (const auto& name : writes) {
    auto* sub = app.get_subcommand(name);
    if (sub == nullptr || name == "merge") continue;
    sub->add_option_function<double>(
        "--max-wall", [](double s) { set_wall_limit(s); },
        "wall-clock limit of each row in seconds (a run; a stability row's whole bisection; one "
        "method's region or analysis): a row over it ends with status timeout (region, "
        "analyze: 'stopped') and the study goes on (default 0: none)");
  }
  for (const auto& name : writes) {
    if (auto* sub = app.get_subcommand(name)) {
      sub->add_flag_function(
          "--force", [](std::int64_t) { set_force_output(true); },
          "replace results of a different spec in --out (default: refuse them)");
    }
  }
}

int g_command_exit_code = 0;

int interrupted_exit(int sig) {
  remove_created_output_dirs();  // only folders this run created and left empty
  std::cerr << "stiffbench: interrupted by " << (sig == SIGTERM ? "SIGTERM" : "SIGINT")
            << ": the run in progress was abandoned; files already written are complete\n";
  return 128 + (sig > 0 ? sig : SIGINT);
}

}  // namespace

void set_command_exit_code(int code) { g_command_exit_code = code; }

namespace {

// Every argument may end up in a JSON record (paths, names, the command line), which holds UTF-8
// only: a byte sequence that is not UTF-8 is refused before anything runs (one message on
// stderr), not found when the record is written after the computation.
bool arguments_are_utf8(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (!valid_utf8(argv[i])) {
      std::cerr << "stiffbench: argument " << i << " ('" << printable(argv[i])
                << "') is not valid UTF-8: paths and names are recorded in the JSON files, "
                   "which hold UTF-8 text; rename the file or folder\n";
      return false;
    }
  return true;
}

// The counters a command is judged by, as it found them: a program (or a test) that calls
// cli_main several times judges each call by its own runs only.
struct CountersBefore {
  long audit_failures = audit_failed_checks();
  long faults = fault_count();
  long plots = failed_plot_count();
};

// Whether argv[1], when it is a command name, is one of the app's commands (else the message).
bool known_command(CLI::App& app, int argc, char** argv) {
  if (argc <= 1 || argv[1][0] == '-') return true;
  std::vector<std::string> names;
  bool known = false;
  for (const auto* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    names.push_back(sub->get_name());
    known = known || sub->get_name() == argv[1];
  }
  if (!known)
    std::cerr << "stiffbench: unknown command '" << argv[1] << "'" << did_you_mean(argv[1], names)
              << "; known: " << join(names) << "\n";
  return known;
}

// Parses and runs the command (subcommands registered by add_*_command run inside parse(), their
// callbacks, so one try covers parsing and running). The exit code when it did not complete.
std::optional<int> parse_and_run(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
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
  return std::nullopt;
}

// The exit code of a command that ran to its end.
int completed_exit_code(const CountersBefore& before) {
  // A signal that arrived after the last run (while a table or plot was written): the results
  // are complete, but the exit code still says the command was interrupted.
  if (const int sig = interrupt_requested()) return interrupted_exit(sig);
  // A run that ended with status error (the model or the integrator threw mid-run) is a failed
  // row: its table was written, and the exit code says so (README).
  if (const long faults = fault_count() - before.faults; faults > 0) {
    std::cerr << "stiffbench: " << faults << " run" << (faults == 1 ? "" : "s")
              << " ended with status error or timeout (see the status and message columns)\n";
    return kExitRowsFailed;
  }
  // A plot that gnuplot did not complete (its warning above): the tables are written, the
  // command still fails so that a script notices.
  if (const long plots = failed_plot_count() - before.plots; plots > 0) {
    std::cerr << "stiffbench: " << plots << " plot" << (plots == 1 ? "" : "s")
              << " not written (see the warnings above); the tables are complete\n";
    return 1;
  }
  // `stiffbench audit`: a claim that does not hold (status fail) fails the command.
  if (const long failed = audit_failed_checks() - before.audit_failures; failed > 0) {
    std::cerr << "stiffbench: " << failed << " audit check" << (failed == 1 ? "" : "s")
              << " failed (status fail in audit.csv; the reason column says why)\n";
    return kExitRowsFailed;
  }
  return g_command_exit_code;
}

}  // namespace

int cli_main(int argc, char** argv) {
  set_command_line(argc, argv);
  g_command_exit_code = 0;
  const CountersBefore before;
  const struct ForgetCommandLine {
    ~ForgetCommandLine() { clear_command_line(); }
  } forget;
  CLI::App app{
      "stiffbench: a testbed comparing time integrators on stiff ODEs from physically based "
      "simulation.\nExit codes: 0 success, 2 bad input, 3 a row ended with status error or timeout "
      "or an audit check failed (its table is written), 130/143 interrupted by SIGINT/SIGTERM, 1 "
      "other errors (compare: the runs differ)."};
  app.require_subcommand(1);
  // Method files: the search path (STIFFBENCH_METHOD_PATH and --methods DIR) is loaded once the
  // command line is parsed, before the command runs (experiments/framework/catalog.hpp).
  auto method_dirs = std::make_shared<std::vector<std::string>>();
  app.add_option("--methods", *method_dirs,
                 "load every method file (*.toml) in DIR, like the folders of "
                 "STIFFBENCH_METHOD_PATH (repeatable; give it before the command)")
      ->type_name("DIR")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.parse_complete_callback([method_dirs] { load_method_search_path(*method_dirs); });

  add_list_commands(app);
  add_solve_command(app);
  add_report_command(app);
  add_profile_command(app);
  add_study_commands(app);
  add_plot_command(app);
  add_run_commands(app);
  add_compare_command(app);

  add_run_limits(app);
  // --max-wall and --force are reset when cli_main returns.
  const struct ForgetSettings {
    ForgetSettings() { set_force_output(false); }
    ~ForgetSettings() {
      set_wall_limit(0);
      set_force_output(false);
    }
  } forget_settings;
  if (!known_command(app, argc, argv)) return 2;
  if (!arguments_are_utf8(argc, argv)) return 2;
  // SIGINT/SIGTERM: the runs stop at their next poll, and the exit code is 128 + signal.
  const InterruptHandlers handlers;
  if (const auto code = parse_and_run(app, argc, argv)) return *code;
  return completed_exit_code(before);
}

}  // namespace stiffbench

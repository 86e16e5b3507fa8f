// Command-line registration of the experiment subcommands (linked into the stiffbench binary
// only; the experiments themselves live in the stiffbench_experiments library so tests and
// other programs call them directly). Each add_*_command adds one subcommand whose callback
// runs the experiment; BadInput thrown there becomes exit code 2 in main().
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "experiments/output/plotting.hpp"

namespace stiffbench {

// Flags every one-off experiment shares; `params` collects --param key=value.
struct CommonFlags {
  std::string model;
  std::string integrators;
  std::vector<std::string> params;
  std::string out_dir = "results";
  PlotOptions plot;
};
// Adds --model (when model_required is not null: required or not), --integrators, --param,
// --out and --svg.
void add_common_flags(CLI::App* cmd, CommonFlags& f, bool with_model, bool model_required);

// One subcommand per registered study (cli/cli_study.cpp).
void add_study_commands(CLI::App& app);
void add_list_commands(CLI::App& app);    // list, describe (cli/cli_list.cpp)
void add_solve_command(CLI::App& app);    // cli/cli_solve.cpp
void add_report_command(CLI::App& app);   // cli/cli_report.cpp
void add_profile_command(CLI::App& app);  // cli/cli_report.cpp
void add_plot_command(CLI::App& app);
void add_run_commands(CLI::App& app);     // run SPEC.toml and merge (cli/cli_run.cpp)
void add_compare_command(CLI::App& app);  // compare OLD NEW (cli/cli_compare.cpp)

// A command's own exit code for cli_main to return when nothing else failed (compare: 1 when the
// runs differ); reset to 0 at the start of each cli_main call.
void set_command_exit_code(int code);

}  // namespace stiffbench

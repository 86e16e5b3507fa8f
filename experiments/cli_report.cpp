// `stiffbench report [SUITE...]` (experiments/report.cpp).
#include <iostream>
#include <memory>

#include "experiments/cli.hpp"
#include "experiments/commands.hpp"
#include "experiments/output.hpp"

namespace stiffbench {

void add_report_command(CLI::App& app) {
  auto opt = std::make_shared<ReportOptions>();
  auto* report = app.add_subcommand(
      "report",
      "run a suite of spec files (default: the built-in suite, experiments/specs/report/) and "
      "write DIR/REPORT.md with one section per spec");
  report->add_option("suite", opt->suite,
                     "a folder of spec files (run in name order) or spec files, one section each "
                     "(default: the built-in suite)");
  report->add_option("--out", opt->out_dir, "output directory")->capture_default_str();
  report->add_flag("--quick", opt->quick,
                   "apply each spec's [quick] overrides (fewer step sizes: a smoke run)");
  report->add_flag("--svg", opt->svg, "also write each plot as SVG");
  report->add_flag("--html", opt->html,
                   "also write DIR/report.html: one self-contained page with every section, the "
                   "plots as inline SVG, sortable tables and the run metadata (implies --svg)");
  report->callback([opt]() {
    opt->force = force_output();
    cmd_report(*opt, std::cout, std::cerr);
  });
}

}  // namespace stiffbench

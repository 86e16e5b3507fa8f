// `stiffbench report [SUITE...]` (experiments/commands/report.cpp) and `stiffbench profile SUITE`
// (experiments/commands/profile.cpp).
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli/cli.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/commands/profile.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

void add_report_command(CLI::App& app) {
  auto opt = std::make_shared<ReportOptions>();
  auto* report = app.add_subcommand("report", command_entry("report").summary);
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

void add_profile_command(CLI::App& app) {
  struct State {
    ProfileOptions opt;
    std::vector<std::string> taus = {"1e-3", "1e-6"}, costs = {"f_evals", "wall"};
  };
  auto st = std::make_shared<State>();
  auto* profile = app.add_subcommand("profile", command_entry("profile").summary);
  profile->add_option("suite", st->opt.suite, "a built-in suite (stiff, mechanical) or a folder")
      ->required();
  profile->add_option("--tau", st->taus, "target accuracies, comma-separated (error <= tau)")
      ->delimiter(',')
      ->capture_default_str();
  profile->add_option("--cost", st->costs, "cost measures: f_evals, wall, linear_solves")
      ->delimiter(',')
      ->capture_default_str();
  profile->add_option("--out", st->opt.out_dir, "output directory")->capture_default_str();
  profile->add_flag("--quick", st->opt.quick, "apply each spec's [quick] overrides");
  profile->add_flag("--svg", st->opt.plot.svg, "also write each plot as SVG");
  profile->add_flag("--html", st->opt.html,
                    "also write DIR/profile.html: one self-contained page with every profile "
                    "(inline SVG), the cost tables and rankings (implies --svg)");
  profile->callback([st]() {
    st->opt.taus.clear();
    for (const auto& t : st->taus) st->opt.taus.push_back(parse_real(t, "--tau"));
    st->opt.costs = st->costs;
    st->opt.force = force_output();
    cmd_profile(st->opt, std::cout, std::cerr);
  });
}

}  // namespace stiffbench

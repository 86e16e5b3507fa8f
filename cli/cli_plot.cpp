#include <filesystem>
#include <iostream>
#include <memory>

#include "cli/cli.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/commands/plot.hpp"

namespace stiffbench {

void add_plot_command(CLI::App& app) {
  struct State {
    std::string dir;
    PlotOptions plot;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand("plot", command_entry("plot").summary);
  cmd->add_option("dir", st->dir, "output folder of an experiment or of `stiffbench report`")
      ->required();
  cmd->add_flag("--svg", st->plot.svg, "also write each plot as SVG next to its PNG");
  cmd->callback([st]() {
    if (replot_directory(st->dir, st->plot, std::cout, std::cerr) == 0)
      throw std::runtime_error("no plot could be drawn (is gnuplot installed?)");
  });
}

}  // namespace stiffbench

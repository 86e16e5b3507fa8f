#include "experiments/cli.hpp"

namespace stiffbench {

// TODO(issue 9): the `plot` subcommand is being written; until then it is not registered.
void add_plot_command(CLI::App& /*app*/) {}

}  // namespace stiffbench

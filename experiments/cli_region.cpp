#include "experiments/cli.hpp"

namespace stiffbench {

// TODO(issue 9): the `region` subcommand is being written; until then it is not registered.
void add_region_command(CLI::App& /*app*/) {}

}  // namespace stiffbench

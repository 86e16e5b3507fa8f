#include "experiments/cli.hpp"

namespace stiffbench {

// TODO(issue 9): the `stability` subcommand is being written; until then it is not registered.
void add_stability_command(CLI::App& /*app*/) {}

}  // namespace stiffbench

#include "experiments/cli.hpp"

namespace stiffbench {

// TODO(issue 9): the `energy` subcommand is being written; until then it is not registered.
void add_energy_command(CLI::App& /*app*/) {}

}  // namespace stiffbench

// The whole stiffbench command line as a function. The stiffbench binary's main() only calls
// it; a program that links the library can first add its own models or integrators
// (register_model / register_integrator in experiments/framework/catalog.hpp) and then call it, so
// that its models get `list`, `describe`, `solve` and every experiment by name:
//
//   int main(int argc, char** argv) {
//     stiffbench::register_model({{"my_brusselator", "..."}, {/* ParamSpecs */}, factory});
//     return stiffbench::cli_main(argc, argv);
//   }
//
// Returns the exit code (0 success, 2 bad input, 1 other errors; never calls exit()). Records
// argv as the command line written into every result's metadata.
#pragma once

namespace stiffbench {

int cli_main(int argc, char** argv);

}  // namespace stiffbench

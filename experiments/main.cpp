// stiffbench: the command-line program (experiments/cli_main.hpp).
#include "experiments/cli_main.hpp"

int main(int argc, char** argv) { return stiffbench::cli_main(argc, argv); }

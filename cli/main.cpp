// stiffbench: the command-line program (cli/cli_main.hpp).
#include "cli/cli_main.hpp"

int main(int argc, char** argv) { return stiffbench::cli_main(argc, argv); }

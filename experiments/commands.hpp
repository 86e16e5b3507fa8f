// The subcommands of `stiffbench`, callable from main() and from tests.
#pragma once

#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

#include "experiments/convergence.hpp"

namespace stiffbench {

void cmd_list(const std::string& what, std::ostream& out);
void cmd_describe(const std::string& name, std::ostream& out);

struct SolveOptions {
  std::string model, integrator;
  Params params;
  // NaN: not given (adaptive mode / the model's default end time).
  double h = std::numeric_limits<double>::quiet_NaN();
  double t_end = std::numeric_limits<double>::quiet_NaN();
  long outputs = 100;
  std::string out_csv;  // empty: no trajectory file; with frames > 0, the output directory
  long frames = 0;      // > 0: write frames + observables.csv into the directory out_csv
  std::string frame_format = "vtu";  // vtu (+ frames.pvd) or vtk (legacy)
};
void cmd_solve(const SolveOptions& opt, std::ostream& out, std::ostream& err);

struct ReportOptions {
  std::string out_dir = "results";
  bool quick = false;
  bool svg = false;
};
void cmd_report(const ReportOptions& opt, std::ostream& out, std::ostream& err);

}  // namespace stiffbench

// `stiffbench solve`: one run (experiments/commands/list_describe.hpp, cmd_solve).
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <utility>

#include "cli/cli.hpp"
#include "core/types.hpp"
#include "experiments/commands/list_describe.hpp"

namespace stiffbench {

void add_solve_command(CLI::App& app) {
  struct State {
    SolveOptions opt;
    std::vector<std::string> params;
    std::string times;
  };
  auto st = std::make_shared<State>();
  SolveOptions& o = st->opt;
  auto* solve = app.add_subcommand("solve", command_entry("solve").summary);
  solve->add_option("--model", o.model, "model name")->required();
  solve
      ->add_option("--integrator", o.integrator,
                   "integrator name, or the path of a method file (*.toml)")
      ->required();
  solve->add_option("--h", o.h,
                    "step size (the run takes N = round(T/h) steps of T/N); omit for the adaptive "
                    "mode of a reference integrator or the model's suggested step");
  solve->add_option("--t-end", o.t_end, "final time (default: the model's literature end time)");
  solve->add_option("--outputs", o.outputs, "number of output intervals in the trajectory")
      ->capture_default_str();
  solve->add_option("--param", st->params, "model/integrator parameter key=value (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  solve->add_option("--out", o.out_csv,
                    "trajectory CSV file (columns t,y0,y1,...; no spec is recorded beside it, "
                    "so an existing file is refused unless --force); with --frames, the output "
                    "directory (its solve.json records the spec)");
  solve->add_option("--frames", o.frames,
                    "write N+1 equally spaced frames into the --out directory: VTK particle "
                    "frames (frame_NNNN.vtu, frames.pvd) for particle models, trajectory.csv "
                    "otherwise, and observables.csv");
  solve->add_option("--times", st->times,
                    "output times t1,t2,... (increasing, in (t0, t_end]; without --t-end the run "
                    "ends at the last) instead of --outputs: adaptive integrators stop exactly at "
                    "each (no interpolation); fixed-step runs report the nearest step and print "
                    "and write its actual t. --out gets one row per time");
  solve->add_option("--log-outputs", o.log_outputs,
                    "N output times log-spaced in t - t0 from --log-first to t_end: t_k = t0 + "
                    "(t1 - t0)*((t_end - t0)/(t1 - t0))^((k-1)/(N-1)); default t1 = t0 + "
                    "(t_end - t0)*10^-(N-1), one per decade; same stops as --times");
  solve->add_option("--log-first", o.log_first,
                    "first time of --log-outputs (default: N-1 decades before t_end)");
  solve
      ->add_option("--frame-format", o.frame_format,
                   "particle frame files: vtu (VTK XML + frames.pvd) or vtk (legacy); a CSV "
                   "copy of each frame is always written for gnuplot")
      ->check(CLI::IsMember({"vtu", "vtk"}))
      ->capture_default_str();
  solve->callback([st, solve]() {
    // A real flag given as nan or inf is named as such (not taken for "not given").
    for (const auto& [flag, value] : {std::pair<const char*, double>{"--t-end", st->opt.t_end},
                                      {"--h", st->opt.h},
                                      {"--log-first", st->opt.log_first}})
      require_input(!solve->count(flag) || std::isfinite(value),
                    std::string(flag) + ": '" + solve->get_option(flag)->as<std::string>() +
                        "' is not a finite number");
    st->opt.params = Params::from_assignments(st->params);
    if (solve->count("--times")) st->opt.times = parse_times(st->times);
    cmd_solve(st->opt, std::cout, std::cerr);
  });
}

}  // namespace stiffbench

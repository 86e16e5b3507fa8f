#include <iostream>
#include <memory>

#include "experiments/catalog.hpp"
#include "experiments/cli.hpp"
#include "experiments/energy.hpp"
#include "experiments/output.hpp"

namespace stiffbench {

void add_energy_command(CLI::App& app) {
  struct State {
    CommonFlags flags;
    EnergySpec spec;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(
      "energy",
      "energy drift of long fixed-step runs: the relative error of an invariant after every "
      "step, sampled with the maximum between samples, its maximum, final value, drift rate "
      "and growth ratio; writes energy.{csv,md,json,png} and energy_summary.csv");
  add_common_flags(cmd, st->flags, true, true);
  cmd->get_option("--integrators")->required();
  cmd->add_option("--h", st->spec.h,
                  "step size (the run takes N = round(T/h) steps of T/N; default: the model's "
                  "suggested step, where it has one)");
  cmd->add_option("--t-end", st->spec.t_end,
                  "final time (default: the model's literature end time, where it has one)");
  cmd->add_option("--samples", st->spec.samples,
                  "rows per integrator in energy.csv (every ceil(N/samples) steps, each with the "
                  "maximum error since the previous row)")
      ->capture_default_str();
  cmd->add_option("--invariant", st->spec.invariant,
                  "which invariant of the model is measured (see `stiffbench describe MODEL`)")
      ->capture_default_str();
  cmd->callback([st]() {
    EnergySpec& spec = st->spec;
    spec.model = st->flags.model;
    spec.integrators = split_list(st->flags.integrators, "--integrators");
    spec.params = Params::from_assignments(st->flags.params);
    spec.validate();
    const std::filesystem::path dir = st->flags.out_dir;
    require_output_dir(dir);
    check_study_output(dir, "energy", spec.to_json(), force_output(), &std::cerr,
                       {"energy_summary.csv"});
    const EnergyResult res = run_energy(spec, &std::cerr);
    const bool plotted = write_energy_outputs(dir, spec, res, st->flags.plot, std::cerr);
    std::cout << energy_markdown_table(res).to_markdown();
    for (const auto& run : res.runs)
      if (run.stats.status != Status::ok)
        std::cout << run.integrator << ": " << run.stats.message << "\n";
    std::cout << "\nwrote " << (dir / "energy").string() << ".{csv,md,json} and "
              << (dir / "energy_summary.csv").string() << "\n";
    if (plotted) std::cout << "plot: " << (dir / "energy.png").string() << "\n";
  });
}

}  // namespace stiffbench

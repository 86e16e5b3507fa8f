#include <iostream>
#include <memory>

#include "experiments/catalog.hpp"
#include "experiments/cli.hpp"
#include "experiments/output.hpp"
#include "experiments/region.hpp"

namespace stiffbench {

void add_region_command(CLI::App& app) {
  struct State {
    CommonFlags flags;
    RegionSpec spec;
    std::string box;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(
      "region",
      "linear stability regions from the coefficients: the boundary |R(z)| = 1 of each "
      "integrator in the complex plane z = h*lambda, and its real-axis, imaginary-axis and "
      "oscillator limits; writes region.{csv,md,json,png} and region_limits.csv");
  add_common_flags(cmd, st->flags, false, false);
  cmd->get_option("--integrators")
      ->description(
          "comma-separated integrator names (default: every integrator with a fixed stability "
          "region or oscillator limit)");
  cmd->add_option("--box", st->box,
                  "the part of the complex plane drawn: re_min,re_max,im_min,im_max (default: "
                  "fitted to the chosen methods' boundaries)");
  cmd->add_option("--resolution", st->spec.resolution, "grid cells per side of the box")
      ->capture_default_str();
  cmd->callback([st]() {
    RegionSpec& spec = st->spec;
    require_input(st->flags.params.empty(),
                  "--param does not apply to region: a stability region depends only on the "
                  "method's coefficients");
    if (!st->flags.integrators.empty())
      spec.integrators = split_list(st->flags.integrators, "--integrators");
    if (!st->box.empty()) spec.box = parse_region_box(st->box);
    spec.validate();
    const std::filesystem::path dir = st->flags.out_dir;
    require_output_dir(dir);
    check_study_output(dir, "region", spec.to_json(), force_output(), &std::cerr,
                       {"region_limits.csv"});
    const RegionResult res = run_region(spec);
    write_region_outputs(dir, spec, res);
    std::cout << region_limits_markdown_table(res).to_markdown();
    std::cout << "\nwrote " << (dir / "region").string() << ".{csv,md,json} and "
              << (dir / "region_limits.csv").string() << "\n";
    if (plot_region(dir / "region.csv", "Stability regions: boundary |R(z)| = 1", st->flags.plot,
                    std::cerr))
      std::cout << "plot: " << (dir / "region.png").string() << "\n";
  });
}

}  // namespace stiffbench

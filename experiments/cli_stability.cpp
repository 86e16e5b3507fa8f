#include <iostream>
#include <memory>

#include "experiments/catalog.hpp"
#include "experiments/cli.hpp"
#include "experiments/output.hpp"
#include "experiments/stability.hpp"

namespace stiffbench {

void add_stability_command(CLI::App& app) {
  struct State {
    CommonFlags flags;
    StabilitySpec spec;
    std::string sweep;
    double horizon = 0;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(
      "stability",
      "largest stable fixed step h_max per integrator (bisection) against the linear-theory "
      "prediction from the system's spectrum; writes stability.{csv,md,json,png}");
  add_common_flags(cmd, st->flags, true, true);
  cmd->get_option("--integrators")->required();
  cmd->add_option("--sweep", st->sweep,
                  "repeat over a model parameter: NAME=v1,v2,... or NAME=lo:hi:n (n log-spaced "
                  "values) and fit the log-log slope of h_max against it");
  cmd->add_option("--rel-tol", st->spec.rel_tol, "relative bisection tolerance on h_max")
      ->capture_default_str();
  cmd->add_option("--periods", st->spec.periods,
                  "horizon of each run in periods 2*pi/omega of the fastest mode")
      ->capture_default_str();
  cmd->add_option("--min-steps", st->spec.min_steps, "each run takes at least this many steps")
      ->capture_default_str();
  cmd->add_option("--horizon", st->horizon,
                  "horizon of each run as a time (instead of --periods; needed when the model "
                  "gives no spectrum)");
  cmd->add_option("--growth", st->spec.growth,
                  "mechanical systems: a run is unstable when its energy exceeds E0 + "
                  "(growth - 1)|E0| at any step")
      ->capture_default_str();
  cmd->add_option("--criterion", st->spec.criterion,
                  "auto (energy for mechanical systems with an energy invariant, else the norm), "
                  "energy, or norm (for models whose energy has an arbitrary zero, e.g. "
                  "gravity)")
      ->capture_default_str();
  cmd->add_option("--norm-growth", st->spec.norm_growth,
                  "a run is unstable when its max-norm exceeds this factor times max(1, |y0|)")
      ->capture_default_str();
  cmd->add_option("--perturbation", st->spec.perturbation,
                  "relative random perturbation of the initial state that excites every mode")
      ->capture_default_str();
  cmd->add_option("--seed", st->spec.seed, "seed of the perturbation")->capture_default_str();
  cmd->add_option("--h-cap-factor", st->spec.h_cap_factor,
                  "largest step tried, in units of 2/omega (A-stable methods are reported "
                  "stable_up_to it)")
      ->capture_default_str();
  cmd->add_option("--max-steps", st->spec.max_steps, "step budget of one run")
      ->capture_default_str();
  cmd->add_option("--ray", st->spec.ray,
                  "where the stiffness() estimate is placed when the spectrum is not computed: "
                  "auto (imaginary axis for mechanical systems, real axis otherwise), imag, real")
      ->capture_default_str();
  cmd->add_option("--dense-limit", st->spec.dense_limit,
                  "compute the exact spectrum (dense eigensolver) up to this dimension")
      ->capture_default_str();
  cmd->callback([st]() {
    StabilitySpec& spec = st->spec;
    spec.model = st->flags.model;
    spec.integrators = split_list(st->flags.integrators, "--integrators");
    spec.params = Params::from_assignments(st->flags.params);
    if (!st->sweep.empty()) parse_sweep(st->sweep, spec.sweep_param, spec.sweep_values);
    if (st->horizon != 0) spec.horizon = st->horizon;
    spec.validate();
    const std::filesystem::path dir = st->flags.out_dir;
    require_output_dir(dir);
    check_study_output(dir, "stability", spec.to_json(), force_output(), &std::cerr);
    const StabilityResult res = run_stability(spec, &std::cerr);
    write_stability_outputs(dir, spec, res);
    std::cout << stability_table(res).to_markdown();
    for (const auto& f : res.fits)
      if (f.measured_slope)
        std::cout << "slope of log h_max vs log " << spec.sweep_param << ", " << f.integrator
                  << ": " << format_fixed(*f.measured_slope, 3)
                  << (f.predicted_slope ? " (predicted " + format_fixed(*f.predicted_slope, 3) + ")"
                                        : std::string())
                  << "\n";
    std::cout << "\nwrote " << (dir / "stability").string() << ".{csv,md,json}\n";
    if (plot_stability(dir / "stability.csv", "Stability limit: " + spec.model, st->flags.plot,
                       std::cerr))
      std::cout << "plot: " << (dir / "stability.png").string() << "\n";
  });
}

}  // namespace stiffbench

#include "cli/cli.hpp"

namespace stiffbench {

void add_common_flags(CLI::App* cmd, CommonFlags& f, bool with_model, bool model_required) {
  if (with_model) {
    auto* m = cmd->add_option("--model", f.model, "model name (see `stiffbench list models`)");
    if (model_required) m->required();
  }
  cmd->add_option("--integrators", f.integrators,
                  "comma-separated integrator names (see `stiffbench list integrators`) or "
                  "method-file paths (*.toml)");
  cmd->add_option("--param", f.params, "model/integrator parameter key=value (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--out", f.out_dir, "output directory")->capture_default_str();
  cmd->add_flag("--svg", f.plot.svg, "also write each plot as SVG next to its PNG");
}

}  // namespace stiffbench

// One subcommand per registered study (experiments/framework/study.hpp): its flags come from the
// study's option declarations (`t_end` is `--t-end`), and its callback runs the study pipeline.
#include <iostream>
#include <map>
#include <memory>

#include "cli/cli.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

namespace {

void add_study_command(CLI::App& app, const StudyKind& kind) {
  struct State {
    CommonFlags flags;
    std::map<std::string, std::string> values;  // option key -> text as given
    std::vector<std::string> positional;        // integrators given without --integrators
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(kind.name, kind.summary);
  add_common_flags(cmd, st->flags, kind.takes_model, kind.takes_model && kind.model_required);
  if (kind.integrators_required)
    cmd->get_option("--integrators")->required();
  else
    cmd->get_option("--integrators")
        ->description(!kind.integrators_help.empty()
                          ? kind.integrators_help
                          : "comma-separated integrator names or method-file paths (default: "
                            "every integrator the study applies to)");
  if (kind.positional_integrators)
    cmd->add_option("methods", st->positional,
                    "integrator names or method-file paths, comma- or space-separated (as "
                    "--integrators)");
  std::vector<std::pair<std::string, CLI::Option*>> given;
  for (const auto& o : kind.options) {
    std::string help = o.help;
    if (!o.choices.empty()) help += " (one of: " + join(o.choices, ", ") + ")";
    // A boolean option that is off by default is a flag: `--probe-unbounded` sets it
    // (`--probe-unbounded=false` too is accepted); the spec-file key takes true/false.
    const bool flag = o.type == ParamType::boolean && o.default_value == "false";
    auto* opt = flag ? cmd->add_flag(option_flag(o.key), st->values[o.key], help)
                     : cmd->add_option(option_flag(o.key), st->values[o.key], help);
    if (!flag)
      opt->type_name(o.type == ParamType::real      ? "FLOAT"
                     : o.type == ParamType::integer ? "INT"
                     : o.type == ParamType::boolean ? "BOOL"
                                                    : "TEXT");
    if (!o.default_value.empty() && !flag) opt->default_str(o.default_value);
    for (const auto& r : kind.required)
      if (r == o.key) opt->required();
    given.emplace_back(o.key, opt);
  }
  cmd->callback([st, given, name = kind.name]() {
    Params options;
    for (const auto& [key, opt] : given)
      if (opt->count() > 0) options.set(key, st->values.at(key));
    StudyTarget target;
    target.model = st->flags.model;
    target.params = Params::from_assignments(st->flags.params);
    if (!st->flags.integrators.empty())
      target.integrators = split_list(st->flags.integrators, "--integrators");
    for (const auto& item : st->positional)
      for (auto& method : split_list(item, "integrators"))
        target.integrators.push_back(std::move(method));
    StudyContext ctx;
    ctx.force = force_output();
    ctx.plot = st->flags.plot;
    ctx.progress = &std::cerr;
    ctx.out = &std::cout;
    ctx.err = &std::cerr;
    run_study(name, std::move(target), options, st->flags.out_dir, ctx);
  });
}

}  // namespace

void add_study_commands(CLI::App& app) {
  for (const auto& kind : study_kinds()) add_study_command(app, kind);
}

}  // namespace stiffbench

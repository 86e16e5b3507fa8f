// `stiffbench list` and `stiffbench describe`.
#include <iostream>
#include <memory>

#include "cli/cli.hpp"
#include "experiments/commands/catalog_markdown.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/framework/catalog.hpp"

namespace stiffbench {

void add_list_commands(CLI::App& app) {
  struct ListState {
    std::string what, format = "text";
  };
  auto ls = std::make_shared<ListState>();
  auto* list = app.add_subcommand("list", "list models, integrators or experiments");
  list->add_option("what", ls->what, "models | integrators | experiments (default: all)")
      ->check(CLI::IsMember({"models", "integrators", "experiments"}));
  list->add_option("--format", ls->format,
                   "text, or markdown: the model or integrator table of the manual "
                   "(docs/models.md, docs/integrators.md)")
      ->check(CLI::IsMember({"text", "markdown"}))
      ->capture_default_str();
  list->callback([ls]() {
    if (ls->format == "markdown") {
      require_input(ls->what == "models" || ls->what == "integrators",
                    "--format markdown: give `models` or `integrators`");
      write_catalog_markdown(ls->what, std::cout);
      return;
    }
    cmd_list(ls->what, std::cout);
    if (ls->what.empty() || ls->what == "integrators") {
      // The methods loaded from files (the search path, --methods, paths given earlier).
      std::vector<std::string> files;
      for (const auto& e : integrator_registry().entries())
        if (const std::string f = method_file_source(e.info.name); !e.built_in && !f.empty())
          files.push_back(e.info.name + " (" + f + ")");
      if (!files.empty()) std::cout << "\nfrom method files: " << join(files) << "\n";
    }
  });

  auto name = std::make_shared<std::string>();
  auto* describe = app.add_subcommand(
      "describe",
      "parameters, defaults and properties of a model, integrator or experiment; a study's "
      "options table");
  describe
      ->add_option("name", *name,
                   "model, integrator or experiment name, or the path of a method file")
      ->required();
  describe->callback(
      [name]() { cmd_describe(resolve_integrator_tokens({*name}).front(), std::cout); });
}

}  // namespace stiffbench

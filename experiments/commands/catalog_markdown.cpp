#include "experiments/commands/catalog_markdown.hpp"

#include <vector>

#include "core/params.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

namespace {

// One Markdown cell: `|` escaped, line breaks as spaces (markdown_escape), an empty cell as "-".
std::string cell(const std::string& text) { return text.empty() ? "-" : markdown_escape(text); }

void write_row(const std::vector<std::string>& cells, std::ostream& out) {
  out << "|";
  for (const auto& c : cells) out << " " << cell(c) << " |";
  out << "\n";
}

void write_header(const std::vector<std::string>& columns, std::ostream& out) {
  write_row(columns, out);
  out << "|";
  for (std::size_t i = 0; i < columns.size(); ++i) out << "---|";
  out << "\n";
}

// Parameter keys in declaration order, as code spans.
std::string param_keys(const std::vector<ParamSpec>& params) {
  std::string s;
  for (const auto& p : params) s += (s.empty() ? "`" : ", `") + p.key + "`";
  return s;
}

std::string count_or_variable(int n) { return n ? std::to_string(n) : "variable"; }

// "fixed", "adaptive" or "fixed, adaptive": what a default-constructed instance supports.
std::string step_modes(const IntegratorRegistry::Entry& e) {
  const auto integ = integrator_registry().create(e.info.name, Params{});
  std::string s;
  if (integ->supports_fixed_step()) s = "fixed";
  if (integ->supports_adaptive()) s += s.empty() ? "adaptive" : ", adaptive";
  return s;
}

void models_table(std::ostream& out) {
  write_header({"model", "kind", "exact", "parameters", "description", "source"}, out);
  for (const auto& e : model_registry().entries()) {
    const ModelInfo& m = e.info;
    write_row({"`" + m.name + "`", m.mechanical ? "mechanical" : "first-order",
               m.exact ? "yes" : "no", param_keys(e.params), m.description, m.source},
              out);
  }
}

void integrators_table(std::ostream& out) {
  write_header({"integrator", "family", "kind", "order", "f per step", "step", "requires",
                "parameters", "description", "literature"},
               out);
  for (const auto& e : integrator_registry().entries()) {
    const MethodInfo& m = e.info;
    write_row({"`" + m.name + "`", to_string(m.family), m.kind, count_or_variable(m.order),
               count_or_variable(m.stages), step_modes(e), describe_requirements(m.requires_),
               param_keys(e.params), m.description, m.reference},
              out);
  }
}

}  // namespace

void write_catalog_markdown(const std::string& what, std::ostream& out) {
  if (what == "models")
    models_table(out);
  else if (what == "integrators")
    integrators_table(out);
  else
    throw BadInput("write_catalog_markdown: unknown catalogue '" + what +
                   "': expected 'models' or 'integrators'");
}

}  // namespace stiffbench

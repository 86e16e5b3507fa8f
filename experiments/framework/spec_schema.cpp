// The spec-file schema of the registered studies (experiments/framework/spec_file.hpp): each kind's
// keys and their types come from the study's option declarations (experiments/framework/study.hpp).
#include "experiments/framework/spec_file.hpp"
#include "experiments/framework/study.hpp"

namespace stiffbench {

namespace {

SpecScalar::Type spec_type(ParamType t) {
  switch (t) {
    case ParamType::real:
      return SpecScalar::Type::real;
    case ParamType::integer:
      return SpecScalar::Type::integer;
    case ParamType::boolean:
      return SpecScalar::Type::boolean;
    case ParamType::text:
      return SpecScalar::Type::text;
  }
  return SpecScalar::Type::text;
}

}  // namespace

const SpecSchema& spec_schema() {
  static SpecSchema schema;
  schema.kinds = study_names();  // studies registered since the last call included
  schema.find = [](const std::string& kind) -> std::optional<SpecKindSchema> {
    const StudyKind* k = find_study(kind);
    if (!k) return std::nullopt;
    SpecKindSchema s;
    s.takes_model = k->takes_model;
    s.model_required = k->model_required;
    s.integrators_required = k->integrators_required;
    for (const auto& o : k->options) s.keys[o.key] = spec_type(o.type);
    return s;
  };
  return schema;
}

std::vector<std::string> spec_kinds() { return study_names(); }

SpecFile load_spec_file(const std::string& file, const std::vector<std::string>& sets) {
  return load_spec_file(file, sets, spec_schema());
}

SpecFile parse_spec_text(const std::string& text, const std::string& file,
                         const std::vector<std::string>& sets) {
  return parse_spec_text(text, file, sets, spec_schema());
}

}  // namespace stiffbench

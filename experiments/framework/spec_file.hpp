// Spec files of `stiffbench run`: one experiment kind per TOML file, keys named like the
// flags of that experiment's command (`--t-end` is `t_end`), model and integrator parameters in
// a [params] table. Any list-valued key (a top-level key other than `integrators`, or a
// parameter) is a sweep dimension. Every error (unknown key, wrong type, empty list, a value a
// flag would refuse) is BadInput naming the file, line and key (README "Spec files and
// sweeps").
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace stiffbench {

// One scalar of a spec: its text (as a --param value would be written) and its TOML type.
struct SpecScalar {
  enum class Type { real, integer, boolean, text };
  Type type = Type::text;
  std::string text;
  nlohmann::json to_json() const;
};

// One key: a scalar, or a list of scalars (a sweep dimension).
struct SpecEntry {
  std::string path;  // "t_end" or "params.n" (the --set spelling)
  std::string key;   // "t_end" or "n"
  std::vector<SpecScalar> values;
  bool is_list = false;
  std::string where;  // "FILE:LINE:COLUMN" or "--set KEY=VALUE"
};

struct SpecFile {
  std::string file;
  std::string kind;                      // convergence | local-error | work-precision | ...
  std::vector<std::string> integrators;  // not a sweep dimension: each point runs all of them
  std::string integrators_where;
  std::vector<SpecEntry> settings;  // top-level keys (model, t_end, ...), sorted by key
  std::vector<SpecEntry> params;    // [params], sorted by key
  // For the report (a suite of spec files, one per section): the section's title and the
  // sentence that explains it, and [quick]: the settings `report --quick` overrides (title and
  // note too). None of them is part of the canonical form.
  // [quick] may also replace `integrators` and set `skip = true` (no section in a quick report).
  std::string title, note;
  std::vector<SpecEntry> quick;
  bool skip = false;               // set by apply_quick
  nlohmann::json to_json() const;  // canonical form (hashed for shards, stored in run.json)
};

// What spec files of one kind may hold: whether the kind takes a model and needs integrators,
// and the type of each of its keys.
struct SpecKindSchema {
  bool takes_model = true;
  bool integrators_required = true;
  std::map<std::string, SpecScalar::Type> keys;
  bool model_required = true;  // false: `model` may be left out (fidelity)
};
// The kinds a reader knows: the registered studies (spec_schema(), from each study's option
// declarations; experiments/framework/spec_schema.cpp), or a schema of a program's own (the fuzz
// targets pass a small one, so that they link without the studies).
struct SpecSchema {
  std::vector<std::string> kinds;
  std::function<std::optional<SpecKindSchema>(const std::string& kind)> find;
};
const SpecSchema& spec_schema();

// The experiment kinds `run` accepts: the registered studies (experiments/framework/study.hpp).
std::vector<std::string> spec_kinds();

// Reads and checks FILE, applies --set KEY=VALUE overrides (VALUE in TOML syntax, e.g. 0.5,
// [8,16], "rk4"; a bare word is a string). Checks keys and value types for the kind; the
// names of models, integrators and parameters are checked when the sweep is expanded.
SpecFile load_spec_file(const std::string& file, const std::vector<std::string>& sets);
SpecFile load_spec_file(const std::string& file, const std::vector<std::string>& sets,
                        const SpecSchema& schema);

// Replaces the settings (and title, note) by the spec's [quick] values.
void apply_quick(SpecFile& spec);

// The same for the text of a spec file; `file` names it in messages.
SpecFile parse_spec_text(const std::string& text, const std::string& file,
                         const std::vector<std::string>& sets);
SpecFile parse_spec_text(const std::string& text, const std::string& file,
                         const std::vector<std::string>& sets, const SpecSchema& schema);

// BadInput with "WHERE: key 'KEY': MESSAGE".
[[noreturn]] void spec_error(const SpecEntry& e, const std::string& message);

}  // namespace stiffbench

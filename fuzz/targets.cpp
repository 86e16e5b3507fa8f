#include "fuzz/targets.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "core/types.hpp"
#include "experiments/framework/spec_file.hpp"
#include "experiments/output/csv.hpp"

namespace stiffbench::fuzz {

void fail(const char* what) { throw std::logic_error(what); }

namespace {
std::vector<std::string> lines_of(std::string_view data) {
  std::vector<std::string> out;
  std::size_t pos = 0;
  while (pos <= data.size()) {
    const std::size_t nl = data.find('\n', pos);
    const std::size_t end = nl == std::string_view::npos ? data.size() : nl;
    out.emplace_back(data.substr(pos, end - pos));
    if (nl == std::string_view::npos) break;
    pos = nl + 1;
  }
  return out;
}
}  // namespace

void params_one(std::string_view data) {
  // Declared parameters of every type, as a model or an integrator declares them.
  static const std::vector<ParamSpec> specs = {
      {"n", ParamType::integer, "8", "size", Bounds::in(1, 4096)},
      {"k", ParamType::real, "1", "stiffness", Bounds::positive()},
      {"rtol", ParamType::real, "1e-6", "tolerance"},  // no declared range: finite only
      {"constrained", ParamType::boolean, "false", "flag"},
      {"linear_solver", ParamType::text, "auto", "solver", {"auto", "dense_lu", "cg"}},
      {"name", ParamType::text, "x", "free text"}};
  try {
    const Params user = Params::from_assignments(lines_of(data));
    std::set<std::string> consumed;
    const Params p = resolve_params(specs, user, &consumed, "fuzz");
    // Every value that passed the check reads back with its type; reals are finite and
    // inside their declared range.
    if (!std::isfinite(p.real("k")) || !std::isfinite(p.real("rtol")))
      fail("a non-finite real passed resolve_params");
    if (!(p.real("k") > 0)) fail("a value outside its declared range passed resolve_params");
    const long n = p.integer("n");
    if (n < 1 || n > 4096) fail("a value outside its declared range passed resolve_params");
    (void)p.boolean("constrained");
    (void)p.text("linear_solver");
    (void)p.text("name");
    std::vector<std::string> keys;
    for (const auto& s : specs) keys.push_back(s.key);
    for (const auto& [key, value] : user.values()) (void)did_you_mean(key, keys);
    check_all_consumed(user, consumed, "fuzz takes n, k, rtol, constrained, linear_solver, name",
                       keys);
  } catch (const BadInput&) {
  }
}

namespace {

// The spec-file schema the fuzz build parses against. The fuzz targets link only the parser
// (scripts/fuzz.sh), not the studies whose option declarations give the program's schema
// (spec_schema()), so this is a copy of their shapes: kinds with a model and keys of every type,
// a sweepable text option, and a kind without a model or required integrators. It exercises the
// same parser paths as the real schema; the real keys are tested in tests/experiments.
const SpecSchema& fuzz_schema() {
  using T = SpecScalar::Type;
  static const std::map<std::string, SpecKindSchema> kinds = {
      {"convergence",
       {true,
        true,
        {{"t_end", T::real},
         {"h", T::real},
         {"levels", T::integer},
         {"refine", T::real},
         {"reference", T::text},
         {"reference_rtol", T::real}}}},
      {"work-precision",
       {true, true, {{"t_end", T::real}, {"levels", T::integer}, {"repeats", T::integer}}}},
      {"stability",
       {true,
        true,
        {{"sweep", T::text}, {"rel_tol", T::real}, {"seed", T::integer}, {"criterion", T::text}}}},
      {"energy", {true, true, {{"h", T::real}, {"t_end", T::real}, {"samples", T::integer}}}},
      {"region", {false, false, {{"box", T::text}, {"resolution", T::integer}}}}};
  static const SpecSchema schema = [] {
    SpecSchema s;
    for (const auto& [name, k] : kinds) s.kinds.push_back(name);
    s.find = [](const std::string& kind) -> std::optional<SpecKindSchema> {
      const auto it = kinds.find(kind);
      if (it == kinds.end()) return std::nullopt;
      return it->second;
    };
    return s;
  }();
  return schema;
}

}  // namespace

void spec_file_one(std::string_view data) {
  // load_spec_file reads a file: one per process, rewritten for every input.
  static const std::string path = [] {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir && *dir ? dir : "/tmp") + "/stiffbench_fuzz_spec_" +
           std::to_string(::getpid()) + ".toml";
  }();
  {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(data.data(), static_cast<std::streamsize>(data.size()));
  }
  try {
    const SpecFile s = load_spec_file(path, {}, fuzz_schema());
    (void)s.to_json().dump();
    if (s.kind.empty()) fail("a spec without a kind was accepted");
  } catch (const BadInput&) {
  }
  std::remove(path.c_str());
}

void csv_one(std::string_view data) {
  const std::string text(data);
  const CsvContent c = parse_run_csv(text);
  for (const auto& [unit, rows] : c.units) {
    if (unit < 0 || rows.lines.empty()) fail("a unit with no rows or a negative index");
    for (const auto& l : rows.lines)
      if (l.empty() || l.back() != '\n') fail("a row without its newline");
  }
  (void)csv_column_values_in(text, "unit_status");
  (void)csv_column_values_in(text, "integrator");
  // Quoting round trip of one line: fields never contain an unquoted separator.
  const auto fields = parse_csv_line(text.substr(0, text.find('\n')));
  if (fields.empty()) fail("parse_csv_line returned no field");
}

}  // namespace stiffbench::fuzz

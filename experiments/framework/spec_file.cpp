#include "experiments/framework/spec_file.hpp"

#include <fstream>

#include <toml++/toml.h>
#include <algorithm>
#include <map>
#include <sstream>

#include "core/params.hpp"
#include "core/types.hpp"
#include "experiments/output/output.hpp"
#include "integrators/method_kinds.hpp"

namespace stiffbench {

namespace {

using Type = SpecScalar::Type;

std::string type_name(Type t) {
  switch (t) {
    case Type::real:
      return "a number";
    case Type::integer:
      return "an integer";
    case Type::boolean:
      return "a boolean";
    case Type::text:
      return "a string";
  }
  return "?";
}

std::string where_of(const std::string& file, const toml::node& n) {
  const auto& s = n.source();
  return file + ":" + std::to_string(s.begin.line) + ":" + std::to_string(s.begin.column);
}

// A scalar node as SpecScalar; BadInput for tables, arrays and dates.
SpecScalar scalar_of(const toml::node& n, const std::string& where, const std::string& path) {
  SpecScalar s;
  if (const auto* v = n.as_floating_point()) {
    s.type = Type::real;
    s.text = format_full(v->get());
  } else if (const auto* i = n.as_integer()) {
    s.type = Type::integer;
    s.text = std::to_string(i->get());
  } else if (const auto* b = n.as_boolean()) {
    s.type = Type::boolean;
    s.text = b->get() ? "true" : "false";
  } else if (const auto* t = n.as_string()) {
    s.type = Type::text;
    s.text = t->get();
  } else {
    throw BadInput(where + ": key '" + path + "': expected a value or a list of values");
  }
  return s;
}

SpecEntry entry_of(const toml::node& n, const std::string& path, const std::string& key,
                   const std::string& where) {
  SpecEntry e;
  e.path = path;
  e.key = key;
  e.where = where;
  if (const auto* arr = n.as_array()) {
    e.is_list = true;
    if (arr->empty()) spec_error(e, "empty list (a sweep needs at least one value)");
    for (const auto& item : *arr) e.values.push_back(scalar_of(item, where, path));
  } else {
    e.values.push_back(scalar_of(n, where, path));
  }
  return e;
}

// Checks the value types of a top-level key against the kind's table.
void check_setting(const SpecKindSchema& schema, const std::string& kind, const SpecEntry& e) {
  std::map<std::string, Type> keys = schema.keys;
  if (schema.takes_model) keys["model"] = Type::text;
  const auto it = keys.find(e.key);
  if (it == keys.end()) {
    std::vector<std::string> known = {"kind", "integrators", "params", "title", "note", "quick"};
    for (const auto& [k, t] : keys) known.push_back(k);
    spec_error(e, "unknown key for a " + kind + " spec" + did_you_mean(e.key, known) +
                      "; known: " + join(known));
  }
  for (const auto& v : e.values) {
    const bool ok = v.type == it->second || (it->second == Type::real && v.type == Type::integer);
    if (!ok) spec_error(e, "expected " + type_name(it->second) + ", got '" + v.text + "'");
  }
}

void put(std::vector<SpecEntry>& list, SpecEntry e) {
  for (auto& x : list) {
    if (x.key == e.key) {
      x = std::move(e);
      return;
    }
  }
  list.push_back(std::move(e));
}

}  // namespace

nlohmann::json SpecScalar::to_json() const {
  switch (type) {
    case Type::real:
      return std::stod(text);
    case Type::integer:
      return std::stol(text);
    case Type::boolean:
      return text == "true";
    case Type::text:
      return text;
  }
  return text;
}

void spec_error(const SpecEntry& e, const std::string& message) {
  throw BadInput(e.where + ": key '" + e.path + "': " + message);
}

nlohmann::json SpecFile::to_json() const {
  nlohmann::json j;
  j["kind"] = kind;
  j["integrators"] = integrators;
  auto value = [](const SpecEntry& e) {
    if (!e.is_list) return e.values.front().to_json();
    nlohmann::json a = nlohmann::json::array();
    for (const auto& v : e.values) a.push_back(v.to_json());
    return a;
  };
  for (const auto& e : settings) j[e.key] = value(e);
  j["params"] = nlohmann::json::object();
  for (const auto& e : params) j["params"][e.key] = value(e);
  return j;
}

namespace {

// toml++ 3.3.0 reaches __builtin_unreachable (undefined behaviour, found by fuzzing: input
// fuzz/regressions/spec_file/toml_unreachable_u_fefb) when a non-ASCII character stands outside
// a string or comment, where TOML allows none anyway. Such text is refused here, before toml++
// sees it: a small scan that skips comments and the four string forms.
void require_ascii_outside_strings(const std::string& text, const std::string& where) {
  int line = 1, column = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    ++column;
    if (c == '\n') {
      ++line;
      column = 0;
      continue;
    }
    if (c == '#') {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
      continue;
    }
    if (c == '"' || c == '\'') {
      const bool multi = text.compare(i, 3, std::string(3, c)) == 0;
      const std::string close = multi ? std::string(3, c) : std::string(1, c);
      std::size_t j = i + close.size();
      while (j < text.size()) {
        if (c == '"' && text[j] == '\\') {
          j += 2;
          continue;
        }
        if (text.compare(j, close.size(), close) == 0) break;
        if (!multi && text[j] == '\n') break;
        if (text[j] == '\n') {
          ++line;
          column = 0;
        }
        ++j;
      }
      column += static_cast<int>(j - i);
      i = std::min(j + close.size(), text.size()) - 1;
      continue;
    }
    if (static_cast<unsigned char>(c) >= 0x80)
      throw BadInput(where + ":" + std::to_string(line) + ":" + std::to_string(column) +
                     ": non-ASCII character outside a string or comment");
  }
}

}  // namespace

SpecFile load_spec_file(const std::string& file, const std::vector<std::string>& sets,
                        const SpecSchema& schema) {
  return parse_spec_text(read_input_file(file, "spec file"), file, sets, schema);
}

namespace {

// [quick]: the settings (and title, note, integrators, skip) `report --quick` applies.
void read_quick(const toml::table& table, const std::string& file, const SpecKindSchema& schema,
                SpecFile& spec) {
  for (const auto& [qk, qnode] : table) {
    const std::string qkey(qk.str());
    SpecEntry e = entry_of(qnode, "quick." + qkey, qkey, where_of(file, qnode));
    if (qkey == "title" || qkey == "note") {
      if (e.is_list || e.values.front().type != Type::text) spec_error(e, "expected a string");
      require_printable(e.values.front().text, where_of(file, qnode), "quick." + qkey,
                        qkey == "note");
    } else if (qkey == "skip") {
      if (e.is_list || e.values.front().type != Type::boolean)
        spec_error(e, "expected true or false");
    } else if (qkey == "integrators") {
      for (const auto& v : e.values)
        if (v.type != Type::text) spec_error(e, "expected integrator names (strings)");
    } else {
      check_setting(schema, spec.kind, e);
    }
    spec.quick.push_back(std::move(e));
  }
}

// --set KEY=VALUE: VALUE parsed as TOML; a bare word that is not TOML is a string.
void apply_sets(const std::vector<std::string>& sets, std::vector<SpecEntry>& settings,
                std::vector<SpecEntry>& params, SpecEntry& integrators) {
  for (const auto& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw BadInput("--set '" + s + "': expected KEY=VALUE (KEY like t_end or params.n)");
    const std::string path = s.substr(0, eq), text = s.substr(eq + 1);
    toml::table parsed;
    try {
      require_ascii_outside_strings("v = " + text, "--set " + s);
      parsed = toml::parse("v = " + text);
    } catch (const BadInput&) {
      parsed = toml::table{{"v", text}};
    } catch (const toml::parse_error&) {
      parsed = toml::table{{"v", text}};
    }
    const std::string where = "--set " + s;
    const toml::node& node = *parsed.get("v");
    if (path == "kind") throw BadInput(where + ": the kind cannot be changed");
    if (path.rfind("params.", 0) == 0) {
      const std::string key = path.substr(7);
      if (key.empty() || key.find('.') != std::string::npos)
        throw BadInput(where + ": expected params.NAME");
      put(params, entry_of(node, path, key, where));
    } else if (path.find('.') != std::string::npos) {
      throw BadInput(where + ": unknown table in '" + path + "' (only params.NAME is dotted)");
    } else if (path == "integrators") {
      integrators = entry_of(node, path, path, where);
    } else {
      put(settings, entry_of(node, path, path, where));
    }
  }
}

// `integrators`: a list of names, or one string "a,b,c" as on the command line.
void read_integrators(const SpecEntry& integrators, const SpecKindSchema& schema, SpecFile& spec) {
  if (!integrators.values.empty()) {
    spec.integrators_where = integrators.where;
    for (const auto& v : integrators.values) {
      if (v.type != Type::text) spec_error(integrators, "expected integrator names (strings)");
      if (!integrators.is_list) {  // "a,b,c" as on the command line
        std::stringstream ss(v.text);
        std::string item;
        while (std::getline(ss, item, ',')) {
          if (item.empty()) spec_error(integrators, "empty name in '" + v.text + "'");
          spec.integrators.push_back(item);
        }
      } else {
        spec.integrators.push_back(v.text);
      }
    }
  } else if (schema.integrators_required) {
    throw BadInput(spec.file + ": key 'integrators' missing (a list of integrator names)");
  }
}

// The TOML document of a spec file (BadInput at the line and column of a syntax error).
toml::table parse_toml(const std::string& source, const std::string& file) {
  try {
    require_ascii_outside_strings(source, file);
    return toml::parse(source, file);
  } catch (const toml::parse_error& err) {
    const auto& b = err.source().begin;
    throw BadInput(file + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": " +
                   std::string(err.description()));
  }
}

// The schema of the document's `kind` (which it sets in spec.kind); BadInput when it is missing,
// unknown or a method file's kind.
SpecKindSchema kind_schema_of(const toml::table& root, const std::string& file,
                              const SpecSchema& schema, SpecFile& spec) {
  const toml::node* kind = root.get("kind");
  if (!kind || !kind->is_string())
    throw BadInput(file + ": key 'kind' missing or not a string; one of " + join(schema.kinds));
  spec.kind = kind->as_string()->get();
  const std::optional<SpecKindSchema> found = schema.find(spec.kind);
  if (!found && is_method_kind(spec.kind))
    throw BadInput(where_of(file, *kind) + ": a method file (kind '" + spec.kind +
                   "'), not a spec file: keep method files out of a folder of specs and name "
                   "them in 'integrators' by path (or load their folder with --methods DIR)");
  if (!found)
    throw BadInput(where_of(file, *kind) + ": key 'kind': unknown kind '" + spec.kind + "'" +
                   did_you_mean(spec.kind, schema.kinds) + "; known: " + join(schema.kinds));
  return *found;
}

}  // namespace

SpecFile parse_spec_text(const std::string& source, const std::string& file,
                         const std::vector<std::string>& sets, const SpecSchema& schema) {
  const toml::table root = parse_toml(source, file);
  SpecFile spec;
  spec.file = file;
  const SpecKindSchema kind_schema = kind_schema_of(root, file, schema, spec);

  std::vector<SpecEntry> settings, params;
  SpecEntry integrators;
  for (const auto& [k, node] : root) {
    const std::string key(k.str());
    const std::string where = where_of(file, node);
    if (key == "kind") continue;
    if (key == "title" || key == "note") {
      const auto* str = node.as_string();
      if (!str) throw BadInput(where + ": key '" + key + "': expected a string");
      require_printable(str->get(), where, key, key == "note");
      (key == "title" ? spec.title : spec.note) = str->get();
      continue;
    }
    if (key == "quick") {
      const auto* table = node.as_table();
      if (!table) throw BadInput(where + ": key 'quick': expected a table ([quick])");
      read_quick(*table, file, kind_schema, spec);
      continue;
    }
    if (key == "params") {
      const auto* table = node.as_table();
      if (!table) throw BadInput(where + ": key 'params': expected a table ([params])");
      for (const auto& [pk, pnode] : *table) {
        const std::string pkey(pk.str());
        params.push_back(entry_of(pnode, "params." + pkey, pkey, where_of(file, pnode)));
      }
      continue;
    }
    if (node.is_table())
      throw BadInput(where + ": key '" + key +
                     "': unknown table (only [params] and [quick] are tables)");
    SpecEntry e = entry_of(node, key, key, where);
    if (key == "integrators")
      integrators = std::move(e);
    else
      settings.push_back(std::move(e));
  }

  apply_sets(sets, settings, params, integrators);
  for (const auto& e : settings) check_setting(kind_schema, spec.kind, e);
  read_integrators(integrators, kind_schema, spec);
  if (kind_schema.takes_model && kind_schema.model_required) {
    const bool has_model = std::any_of(settings.begin(), settings.end(),
                                       [](const auto& e) { return e.key == "model"; });
    if (!has_model) throw BadInput(file + ": key 'model' missing");
  }
  auto by_key = [](const SpecEntry& a, const SpecEntry& b) { return a.key < b.key; };
  std::sort(settings.begin(), settings.end(), by_key);
  std::sort(params.begin(), params.end(), by_key);
  spec.settings = std::move(settings);
  spec.params = std::move(params);
  return spec;
}

void apply_quick(SpecFile& spec) {
  for (const auto& q : spec.quick) {
    if (q.key == "title" || q.key == "note") {
      (q.key == "title" ? spec.title : spec.note) = q.values.front().text;
      continue;
    }
    if (q.key == "skip") {
      spec.skip = q.values.front().text == "true";
      continue;
    }
    if (q.key == "integrators") {
      spec.integrators.clear();
      for (const auto& v : q.values) spec.integrators.push_back(v.text);
      continue;
    }
    SpecEntry e = q;
    e.path = q.key;
    put(spec.settings, std::move(e));
  }
  std::sort(spec.settings.begin(), spec.settings.end(),
            [](const SpecEntry& a, const SpecEntry& b) { return a.key < b.key; });
  spec.quick.clear();
}

}  // namespace stiffbench

#include "experiments/framework/catalog.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <utility>

#include "experiments/output/output.hpp"
#include "integrators/method_file.hpp"
#include "integrators/register.hpp"
#include "models/register.hpp"

namespace stiffbench {

namespace {

ModelRegistry& mutable_model_registry() {
  static ModelRegistry reg = [] {
    ModelRegistry r("model");
    register_problem_models(r);
    register_mass_spring_models(r);
    register_sph_models(r);
    register_grid_models(r);
    return r;
  }();
  return reg;
}

IntegratorRegistry& mutable_integrator_registry() {
  static IntegratorRegistry reg = [] {
    IntegratorRegistry r("integrator");
    register_explicit_integrators(r);
    register_symplectic_integrators(r);
    register_implicit_integrators(r);
    register_graphics_integrators(r);
    register_operator_splitting_integrators(r);
    register_reference_integrators(r);
    return r;
  }();
  return reg;
}

}  // namespace

const ModelRegistry& model_registry() { return mutable_model_registry(); }
const IntegratorRegistry& integrator_registry() { return mutable_integrator_registry(); }

void register_model(ModelRegistry::Entry entry) {
  entry.built_in = false;
  mutable_model_registry().add(std::move(entry));
}

void register_integrator(IntegratorRegistry::Entry entry) {
  entry.built_in = false;
  mutable_integrator_registry().add(std::move(entry));
}

namespace {
double g_memory_limit = 0;  // --max-memory; 0: the available memory

double available_memory() {
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  double kb = 0;
  while (in >> key >> kb) {
    std::getline(in, unit);
    if (key == "MemAvailable:") return kb * 1024.0;
  }
  return 0;  // unknown: only --max-memory and kMaxDimension apply
}

}  // namespace

std::string format_bytes(double bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 6) {
    bytes /= 1024.0;
    ++u;
  }
  char buf[64];
  if (u == 0)
    std::snprintf(buf, sizeof buf, "%.0f bytes", bytes);
  else
    std::snprintf(buf, sizeof buf, "%.3g %s", bytes, units[u]);
  return buf;
}

double parse_memory_size(const std::string& text, const std::string& flag) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    throw BadInput(flag + ": '" + text + "' is not a size (bytes, or a number with K, M, G or T)");
  }
  std::string suffix = text.substr(used);
  if (suffix.size() == 3 && (suffix.substr(1) == "iB" || suffix.substr(1) == "ib"))
    suffix = suffix.substr(0, 1);
  else if (suffix.size() == 2 && (suffix[1] == 'B' || suffix[1] == 'b'))
    suffix = suffix.substr(0, 1);
  double scale = 1;
  if (suffix.empty() || suffix == "B")
    scale = 1;
  else if (suffix == "K" || suffix == "k")
    scale = 1024.0;
  else if (suffix == "M" || suffix == "m")
    scale = 1024.0 * 1024;
  else if (suffix == "G" || suffix == "g")
    scale = 1024.0 * 1024 * 1024;
  else if (suffix == "T" || suffix == "t")
    scale = 1024.0 * 1024 * 1024 * 1024;
  else
    throw BadInput(flag + ": '" + text + "' is not a size (bytes, or a number with K, M, G or T)");
  require_input(std::isfinite(v) && v > 0,
                flag + ": '" + text + "' must be a positive finite size");
  return v * scale;
}

void set_memory_limit(double bytes) { g_memory_limit = bytes; }

double memory_limit(std::string* source) {
  if (g_memory_limit > 0) {
    if (source) *source = "--max-memory";
    return g_memory_limit;
  }
  if (source) *source = "the memory available on this machine (raise or lower with --max-memory)";
  return available_memory();
}

// ---- Methods as files --------------------------------------------------------------------------

namespace {

namespace fs = std::filesystem;

struct LoadedMethodFile {
  std::string path;       // as loaded (relative to the working folder or absolute)
  std::string canonical;  // weakly canonical, to recognise the same file
  std::string text;
};
// The method files registered in this process, by method name.
std::map<std::string, LoadedMethodFile>& loaded_method_files() {
  static std::map<std::string, LoadedMethodFile> files;
  return files;
}

std::string read_text(const std::string& path) { return read_input_file(path, "method file"); }

}  // namespace

bool is_method_file_token(const std::string& token) {
  return token.find('/') != std::string::npos ||
         (token.size() > 5 && token.compare(token.size() - 5, 5, ".toml") == 0);
}

std::string register_method_file(const std::string& given, const std::string& base) {
  const fs::path p =
      base.empty() || fs::path(given).is_absolute() ? fs::path(given) : fs::path(base) / given;
  const std::string path = p.lexically_normal().string();
  std::error_code ec;
  if (fs::is_directory(p, ec))
    throw BadInput(path + ": a folder, not a method file (give folders with --methods DIR)");
  const std::string text = read_text(path);
  const std::string canonical = fs::weakly_canonical(p, ec).string();
  MethodDefinition m = parse_method_file(text, path);
  auto& files = loaded_method_files();
  if (const auto it = files.find(m.name); it != files.end()) {
    // The same file (or one with the same text) again: registered once.
    if (it->second.text == text) return m.name;
    // The same file, edited since this process registered it (a program running several
    // studies): the method is what the file says now, and its hash records the new text.
    if (it->second.canonical == canonical) {
      IntegratorRegistry::Entry entry = method_registry_entry(m);
      entry.built_in = false;
      mutable_integrator_registry().add_or_replace(std::move(entry));
      it->second = {path, canonical, text};
      return m.name;
    }
    throw BadInput(path + ": method '" + m.name + "' is already defined by " + it->second.path +
                   " (a different method); give one of them another name");
  }
  if (const auto* e = mutable_integrator_registry().find(m.name))
    throw BadInput(path + ": method '" + m.name + "' is the name of " +
                   (e->built_in ? "a built-in integrator (" + e->info.description + ")"
                                : std::string("an integrator registered by the program")) +
                   "; give the method in the file another name");
  IntegratorRegistry::Entry entry = method_registry_entry(m);
  entry.built_in = false;
  mutable_integrator_registry().add(std::move(entry));
  files[m.name] = {path, canonical, text};
  return m.name;
}

std::vector<std::string> resolve_integrator_tokens(std::vector<std::string> tokens,
                                                   const std::string& base) {
  for (std::string& t : tokens) {
    if (is_variant_token(t))
      t = register_variant(t, base);
    else if (is_method_file_token(t))
      t = register_method_file(t, base);
  }
  return tokens;
}

namespace {
std::map<std::string, VariantOf>& registered_variants() {
  static std::map<std::string, VariantOf> variants;
  return variants;
}

std::string trimmed_text(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return {};
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}
}  // namespace

bool is_variant_token(const std::string& token) {
  return token.size() > 2 && token.back() == '}' && token.find('{') != std::string::npos;
}

std::optional<VariantOf> variant_of(const std::string& name) {
  const auto& v = registered_variants();
  if (const auto it = v.find(name); it != v.end()) return it->second;
  return std::nullopt;
}

namespace {
// The assignments between the braces of `token` (`label` apart), checked for form only.
Params variant_assignments(const std::string& token, const std::string& what, std::string& label) {
  const auto open = token.find('{');
  const std::string body = token.substr(open + 1, token.size() - open - 2);
  require_input(body.find_first_of("{}") == std::string::npos,
                what + ": braces cannot nest (write METHOD{key=value,...})");
  Params fixed;
  std::stringstream ss(body);
  std::string item;
  while (std::getline(ss, item, ',')) {
    item = trimmed_text(item);
    const auto eq = item.find('=');
    require_input(eq != std::string::npos && eq > 0,
                  what + ": '" + item + "' is not key=value (write METHOD{key=value,...})");
    const std::string key = trimmed_text(item.substr(0, eq));
    const std::string value = trimmed_text(item.substr(eq + 1));
    require_input(!value.empty(), what + ": key '" + key + "' has no value");
    if (key == "label") {
      require_input(label.empty(), what + ": label given twice");
      label = value;
      continue;
    }
    require_input(!fixed.contains(key), what + ": key '" + key + "' given twice");
    fixed.set(key, value);
  }
  require_input(!fixed.empty(), what + ": no parameter (write METHOD{key=value,...})");
  return fixed;
}
}  // namespace

std::string register_variant(const std::string& token, const std::string& base_dir) {
  const std::string what = "integrator variant '" + token + "'";
  const std::string method = trimmed_text(token.substr(0, token.find('{')));
  require_input(!method.empty(), what + ": no method before '{' (write METHOD{key=value,...})");
  std::string label;
  const Params fixed = variant_assignments(token, what, label);
  const std::string base_name =
      is_method_file_token(method) ? register_method_file(method, base_dir) : method;
  const auto& base = integrator_registry().at(base_name);
  // Every key must be one the method declares, with a valid value (the same check as --param).
  std::set<std::string> consumed;
  resolve_params(base.params, fixed, &consumed, what);
  for (const auto& [key, value] : fixed.values())
    if (!consumed.count(key)) {
      std::vector<std::string> keys;
      for (const auto& p : base.params) keys.push_back(p.key);
      throw BadInput(what + ": '" + base_name + "' has no parameter '" + key + "'" +
                     did_you_mean(key, keys) + "; " +
                     integrator_registry().accepted_keys(base_name));
    }
  if (label.empty()) {
    std::string canonical = base_name + "{";
    bool first = true;
    for (const auto& [key, value] : fixed.values()) {
      canonical += (first ? "" : ",") + key + "=" + value;
      first = false;
    }
    label = canonical + "}";
  }
  require_input(printable(label) == label && valid_utf8(label),
                what + ": the label holds a control character");
  auto& variants = registered_variants();
  if (const auto it = variants.find(label); it != variants.end()) {
    if (it->second.base == base_name && it->second.fixed.values() == fixed.values()) return label;
    throw BadInput(what + ": label '" + label + "' is already the variant " + it->second.base +
                   " with other parameters; give this one another label");
  }
  if (const auto* e = integrator_registry().find(label))
    throw BadInput(what + ": label '" + label + "' is the name of " +
                   (e->built_in ? std::string("a built-in integrator") : "another integrator") +
                   "; give the variant another label");
  IntegratorRegistry::Entry entry;
  entry.info = base.info;
  entry.info.name = label;
  std::string assignments;
  for (const auto& [key, value] : fixed.values())
    assignments += (assignments.empty() ? "" : ", ") + key + " = " + value;
  entry.info.description = base.info.description + " (variant: " + assignments + ")";
  for (const auto& p : base.params)
    if (!fixed.contains(p.key)) entry.params.push_back(p);
  entry.make = [base_name, fixed, params = entry.params](const Params& given) {
    Params all = fixed;
    for (const auto& p : params) all.set(p.key, given.text(p.key));
    return integrator_registry().create(base_name, all);
  };
  entry.built_in = false;
  mutable_integrator_registry().add(std::move(entry));
  variants[label] = {base_name, fixed};
  return label;
}

void load_method_search_path(const std::vector<std::string>& dirs) {
  std::vector<std::pair<std::string, std::string>> folders;  // folder, where it was given
  if (const char* env = std::getenv("STIFFBENCH_METHOD_PATH")) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':'))
      if (!item.empty()) folders.emplace_back(item, "STIFFBENCH_METHOD_PATH");
  }
  for (const auto& d : dirs) folders.emplace_back(d, "--methods");
  for (const auto& [dir, origin] : folders) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw BadInput(origin + ": '" + dir + "' is not a folder");
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (e.path().extension() == ".toml" && !fs::is_directory(e.path(), ec))
        files.push_back(e.path().string());
    if (ec) throw BadInput(origin + ": cannot list '" + dir + "': " + ec.message());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) register_method_file(f);
  }
}

std::string method_file_source(const std::string& given) {
  const std::optional<VariantOf> variant = variant_of(given);
  const std::string name = variant ? variant->base : given;
  const auto& files = loaded_method_files();
  if (const auto it = files.find(name); it != files.end()) return it->second.path;
  for (const MethodDefinition& m : built_in_methods())
    if (m.name == name) return m.source;
  return {};
}

nlohmann::json with_method_files(nlohmann::json spec) {
  if (!spec.is_object()) return spec;
  std::vector<std::string> names;
  for (const char* key : {"integrators", "integrator"}) {
    if (!spec.contains(key)) continue;
    const nlohmann::json& v = spec[key];
    if (v.is_string()) names.push_back(v.get<std::string>());
    if (v.is_array())
      for (const auto& x : v)
        if (x.is_string()) names.push_back(x.get<std::string>());
  }
  nlohmann::json files = nlohmann::json::object(), variants = nlohmann::json::object();
  const auto& loaded = loaded_method_files();
  for (const auto& given : names) {
    std::string n = given;
    if (const std::optional<VariantOf> v = variant_of(given)) {
      variants[given] = {{"method", v->base}, {"params", v->fixed.values()}};
      n = v->base;
    }
    if (const auto it = loaded.find(n); it != loaded.end())
      files[n] = {{"file", it->second.path}, {"fnv1a64", hex16(fnv1a64(it->second.text))}};
  }
  if (!files.empty()) spec["method_files"] = files;
  if (!variants.empty()) spec["variants"] = variants;
  return spec;
}

nlohmann::json run_metadata(const std::string& experiment, const nlohmann::json& spec) {
  std::optional<ModelRecord> model;
  if (spec.is_object() && spec.contains("model") && spec["model"].is_string())
    if (const auto* e = model_registry().find(spec["model"].get<std::string>()))
      model = ModelRecord{e->info.name, e->info.description, e->info.source, e->built_in};
  return run_metadata(experiment, with_method_files(spec), model);
}

double parse_real(const std::string& text, const std::string& flag) {
  std::size_t used = 0;
  double v = std::numeric_limits<double>::quiet_NaN();
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  require_input(!text.empty() && used == text.size() && std::isfinite(v),
                flag + ": '" + text + "' is not a finite number");
  return v;
}

std::vector<double> parse_real_list(const std::string& text, const std::string& flag) {
  std::vector<double> out;
  for (const auto& item : split_list(text, flag)) out.push_back(parse_real(item, flag));
  return out;
}

std::vector<std::string> split_list(const std::string& s, const std::string& flag) {
  std::vector<std::string> out;
  std::size_t start = 0;
  // The next comma outside braces (a variant's assignments stay with their method).
  auto next_comma = [&s](std::size_t from) {
    int depth = 0;
    for (std::size_t i = from; i < s.size(); ++i) {
      if (s[i] == '{') ++depth;
      if (s[i] == '}' && depth > 0) --depth;
      if (s[i] == ',' && depth == 0) return i;
    }
    return std::string::npos;
  };
  while (true) {
    const auto comma = next_comma(start);
    const std::string item =
        s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    require_input(!item.empty(), flag + ": empty name in '" + s + "'");
    out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace stiffbench

// A study's options bound to the fields of its typed spec, one line per option:
//
//   const OptionTable<EnergySpec>& energy_options() {
//     static const OptionTable<EnergySpec> t = OptionTable<EnergySpec>()
//         .add("samples", &EnergySpec::samples, "rows per integrator", Bounds::at_least(1))
//         .add("invariant", &EnergySpec::invariant, "which invariant is measured");
//     return t;
//   }
//
// The default of an option is the field's initialiser in a default-constructed Spec (a double
// that is NaN there is an option without default: absent unless given, the field stays NaN).
// From the table come the study's declarations (`StudyKind::options`: flags, spec-file keys,
// sweep axes, `describe`), the reading of resolved options into a spec, the range check of a
// spec a program filled by hand, and the options' part of the spec JSON.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"

namespace stiffbench {

// The shortest decimal text that reads back as `v` (what a user would type: "0.01", "100",
// "1e-7"), "" for NaN.
inline std::string option_default_text(double v) {
  if (std::isnan(v)) return "";
  char buf[40];
  int digits = 1;
  for (; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  std::string text = buf;
  const auto e = text.find('e');
  if (e == std::string::npos) return text;
  const int exponent = std::atoi(text.c_str() + e + 1);
  if (exponent >= 0 && exponent < 16) {  // an integer-sized number: written out ("100")
    std::snprintf(buf, sizeof buf, "%.*g", std::max(digits, exponent + 1), v);
    return buf;
  }
  // "1e-07" -> "1e-7", "1e+20" -> "1e20".
  std::string mantissa = text.substr(0, e), exp = text.substr(e + 1);
  const bool negative = exp[0] == '-';
  exp = exp.substr(exp[0] == '-' || exp[0] == '+' ? 1 : 0);
  exp.erase(0, std::min(exp.find_first_not_of('0'), exp.size() - 1));
  return mantissa + "e" + (negative ? "-" : "") + exp;
}

template <class Spec>
class OptionTable {
 public:
  // Binds a numeric, boolean or text option to `member`.
  template <class T>
  OptionTable& add(std::string key, T Spec::*member, std::string help, Bounds bounds = {}) {
    return bind(std::move(key), member, std::move(help), bounds, {});
  }
  // Binds a text option with its allowed values.
  OptionTable& add(std::string key, std::string Spec::*member, std::string help,
                   std::vector<std::string> choices) {
    return bind(std::move(key), member, std::move(help), Bounds{}, std::move(choices));
  }

  // An option of its own type (a list, a box): its declaration, how it is read from resolved
  // options and how it is written to the spec JSON (nothing: a field recorded elsewhere).
  OptionTable& add(ParamSpec decl, std::function<void(const Params&, Spec&)> read,
                   std::function<void(const Spec&, nlohmann::json&)> json) {
    decls_.push_back(std::move(decl));
    fields_.push_back({std::move(read), [](const Spec&) {}, std::move(json)});
    return *this;
  }

  // The declarations, in table order, defaults from Spec{}.
  const std::vector<ParamSpec>& declarations() const { return decls_; }

  // Every option of `options` (resolved: a declared default is present) into its field; an
  // option without default that was not given leaves the field as it is.
  void read(const Params& options, Spec& spec) const {
    for (const auto& f : fields_) f.read(options, spec);
  }

  // BadInput naming the flag (`--samples must be >= 1 (got 0)`) for a field outside its range
  // or choices: for specs a program filled without the command line's checks.
  void check(const Spec& spec) const {
    for (const auto& f : fields_) f.check(spec);
  }

  // The options' values into the spec JSON (`j[key] = value`).
  void to_json(const Spec& spec, nlohmann::json& j) const {
    for (const auto& f : fields_) f.json(spec, j);
  }

 private:
  struct Field {
    std::function<void(const Params&, Spec&)> read;
    std::function<void(const Spec&)> check;
    std::function<void(const Spec&, nlohmann::json&)> json;
  };

  static std::string flag_of(const std::string& key) {
    std::string flag = "--" + key;
    for (char& c : flag)
      if (c == '_') c = '-';
    return flag;
  }

  template <class T>
  OptionTable& bind(std::string key, T Spec::*member, std::string help, Bounds bounds,
                    std::vector<std::string> choices) {
    const Spec defaults{};
    const T& d = defaults.*member;
    ParamSpec decl;
    decl.key = key;
    decl.help = std::move(help);
    decl.bounds = bounds;
    decl.choices = choices;
    Field f;
    f.json = [key, member](const Spec& s, nlohmann::json& j) { j[key] = s.*member; };
    if constexpr (std::is_same_v<T, bool>) {
      decl.type = ParamType::boolean;
      decl.default_value = d ? "true" : "false";
      f.read = [key, member](const Params& o, Spec& s) { s.*member = o.boolean(key); };
      f.check = [](const Spec&) {};
    } else if constexpr (std::is_integral_v<T>) {
      decl.type = ParamType::integer;
      decl.default_value = std::to_string(d);
      f.read = [key, member](const Params& o, Spec& s) {
        s.*member = static_cast<T>(o.integer(key));
      };
      f.check = [key, member, bounds](const Spec& s) {
        const double v = static_cast<double>(s.*member);
        require_input(!bounds.declared() || bounds.contains(v),
                      flag_of(key) + " must be " + bounds.to_string() + " (got " +
                          std::to_string(s.*member) + ")");
      };
    } else if constexpr (std::is_floating_point_v<T>) {
      decl.type = ParamType::real;
      decl.default_value = option_default_text(d);
      f.read = [key, member](const Params& o, Spec& s) {
        if (o.contains(key)) s.*member = o.real(key);
      };
      f.check = [key, member, bounds](const Spec& s) {
        const double v = s.*member;
        require_input(
            std::isnan(v) || (std::isfinite(v) && (!bounds.declared() || bounds.contains(v))),
            flag_of(key) + " must be " + bounds.to_string() + " (got " + option_default_text(v) +
                ")");
      };
    } else {
      static_assert(std::is_same_v<T, std::string>, "an option is a number, a bool or a text");
      decl.type = ParamType::text;
      decl.default_value = d;
      f.read = [key, member](const Params& o, Spec& s) {
        if (o.contains(key)) s.*member = o.text(key);
      };
      f.check = [key, member, choices](const Spec& s) {
        const std::string& v = s.*member;
        bool ok = choices.empty();
        for (const auto& c : choices) ok = ok || c == v;
        require_input(ok, flag_of(key) + ": '" + v + "' is not one of " + join(choices));
      };
    }
    decls_.push_back(std::move(decl));
    fields_.push_back(std::move(f));
    return *this;
  }

  std::vector<ParamSpec> decls_;
  std::vector<Field> fields_;
};

}  // namespace stiffbench

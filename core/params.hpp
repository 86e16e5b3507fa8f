// Params: the key/value bag built from `--param k=v` flags (and later spec files).
//
// Every consumer (a model or integrator factory) declares the keys it accepts as ParamSpecs;
// the registry fills in defaults, hands the factory only its own keys, and the caller checks
// that every key the user gave was consumed by someone: an unknown or unused key is an error
// naming the key (see Registry::create and check_all_consumed).
#pragma once

#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace stiffbench {

enum class ParamType { real, integer, boolean, text };

// The valid range of a numeric parameter, checked by resolve_params before any model or
// integrator is built, and shown by `describe`. A default-constructed Bounds is "not declared":
// then only finiteness is checked (parameters of models registered from outside the library);
// every built-in numeric parameter declares one (tests/experiments/test_bad_input_catalogue.cpp).
class Bounds {
 public:
  Bounds() = default;
  static Bounds any();                     // every finite value (gravity, an initial coordinate)
  static Bounds positive();                // > 0
  static Bounds non_negative();            // >= 0
  static Bounds at_least(double lo);       // >= lo
  static Bounds above(double lo);          // > lo
  static Bounds in(double lo, double hi);  // [lo, hi]
  static Bounds in_closed_open(double lo, double hi);  // [lo, hi)
  static Bounds in_open_closed(double lo, double hi);  // (lo, hi]

  bool declared() const { return declared_; }
  bool contains(double v) const;
  // "> 0", ">= 1", "in [0, 1)", "any finite value"; "not declared" when not.
  std::string to_string() const;

  // The ends (±infinity when unbounded) and whether each is excluded.
  double lower() const { return lo_; }
  double upper() const { return hi_; }
  bool lower_open() const { return lo_open_; }
  bool upper_open() const { return hi_open_; }

 private:
  Bounds(double lo, bool lo_open, double hi, bool hi_open);
  bool declared_ = false;
  double lo_ = -std::numeric_limits<double>::infinity();
  double hi_ = std::numeric_limits<double>::infinity();
  bool lo_open_ = false, hi_open_ = false;
};

// One declared parameter. Numeric ones give their range, text ones may list their choices:
//   {"k", P::real, "1", "spring stiffness", B::positive()}
//   {"phi", P::text, "sin", "phi(t)", {"sin", "cos", "exp"}}
struct ParamSpec {
  ParamSpec() = default;
  ParamSpec(std::string k, ParamType t, std::string def, std::string h,
            std::vector<std::string> c = {})
      : key(std::move(k)),
        type(t),
        default_value(std::move(def)),
        help(std::move(h)),
        choices(std::move(c)) {}
  ParamSpec(std::string k, ParamType t, std::string def, std::string h, Bounds b)
      : key(std::move(k)), type(t), default_value(std::move(def)), help(std::move(h)), bounds(b) {}

  std::string key;
  ParamType type = ParamType::real;
  std::string default_value;  // as the user would type it
  std::string help;
  std::vector<std::string> choices = {};  // for text parameters: the allowed values (empty: any)
  Bounds bounds = {};                     // for numeric parameters: the valid range
};

std::string to_string(ParamType type);

// A parameter value given from C++: converts from a number, a bool or a string to the text form
// every Params holds (what `--param` would have given). Doubles are written with 17 significant
// digits, so they reach the consumer bit for bit.
class ParamValue {
 public:
  ParamValue(double v);
  ParamValue(int v) : text_(std::to_string(v)) {}
  ParamValue(long v) : text_(std::to_string(v)) {}
  ParamValue(bool v) : text_(v ? "true" : "false") {}
  ParamValue(const char* v) : text_(v) {}
  ParamValue(std::string v) : text_(std::move(v)) {}
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

class Params {
 public:
  Params() = default;
  // Typed construction: Params{{"rtol", 1e-8}, {"linear_solver", "klu"}, {"n", 32}}.
  Params(std::initializer_list<std::pair<std::string, ParamValue>> values) {
    for (const auto& [key, value] : values) set(key, value.text());
  }
  void set(const std::string& key, const ParamValue& value) { set(key, value.text()); }
  void set(const std::string& key, const char* value) { set(key, std::string(value)); }

  // Parses "key=value" strings; a malformed one is BadInput naming it.
  static Params from_assignments(const std::vector<std::string>& assignments);

  void set(const std::string& key, const std::string& value);
  bool contains(const std::string& key) const { return values_.count(key) != 0; }
  const std::map<std::string, std::string>& values() const { return values_; }
  bool empty() const { return values_.empty(); }

  // Typed reads. A missing key is a programming error (std::logic_error): the registry has
  // filled in every declared default. A value that does not parse is BadInput naming the key.
  double real(const std::string& key) const;
  long integer(const std::string& key) const;
  bool boolean(const std::string& key) const;
  const std::string& text(const std::string& key) const;

  // Keys read so far through the typed accessors.
  const std::set<std::string>& read_keys() const { return read_; }

 private:
  const std::string& raw(const std::string& key) const;
  std::map<std::string, std::string> values_;
  mutable std::set<std::string> read_;
};

// Defaults of `specs` overlaid with the user's values for the keys the specs declare. Each
// user key that was taken is added to `consumed`. Values are type- and range-checked here
// (BadInput naming the key, the value, the valid range and `owner`), so a bad value is reported
// before anything is allocated or run.
Params resolve_params(const std::vector<ParamSpec>& specs, const Params& user,
                      std::set<std::string>* consumed, const std::string& owner);

// BadInput naming the first user key that no consumer took, the closest of `known_keys` and what
// each consumer accepts.
void check_all_consumed(const Params& user, const std::set<std::string>& consumed,
                        const std::string& accepted_summary,
                        const std::vector<std::string>& known_keys = {});

// The known names closest to `name` (edit distance at most max(2, |name|/3), or `name` a prefix
// of them), best first, at most three: for "did you mean" hints.
std::vector<std::string> closest_names(const std::string& name,
                                       const std::vector<std::string>& known);
// "; did you mean 'x' or 'y'?" or "" when nothing is close.
std::string did_you_mean(const std::string& name, const std::vector<std::string>& known);

// "k1, k2, k3" for messages.
std::string join(const std::vector<std::string>& items, const std::string& sep = ", ");

}  // namespace stiffbench

// Params: the key/value bag built from `--param k=v` flags (and later spec files).
//
// Every consumer (a model or integrator factory) declares the keys it accepts as ParamSpecs;
// the registry fills in defaults, hands the factory only its own keys, and the caller checks
// that every key the user gave was consumed by someone: an unknown or unused key is an error
// naming the key (see Registry::create and check_all_consumed).
#pragma once

#include <initializer_list>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace stiffbench {

enum class ParamType { real, integer, boolean, text };

struct ParamSpec {
  std::string key;
  ParamType type = ParamType::real;
  std::string default_value;  // as the user would type it
  std::string help;
  std::vector<std::string> choices = {};  // for text parameters: the allowed values (empty: any)
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
// user key that was taken is added to `consumed`. Values are type-checked here, so a bad value
// is reported before any run starts.
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

#include "core/params.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace stiffbench {

std::string to_string(ParamType type) {
  switch (type) {
    case ParamType::real:
      return "real";
    case ParamType::integer:
      return "integer";
    case ParamType::boolean:
      return "bool";
    case ParamType::text:
      return "text";
  }
  return "?";
}

Bounds::Bounds(double lo, bool lo_open, double hi, bool hi_open)
    : declared_(true), lo_(lo), hi_(hi), lo_open_(lo_open), hi_open_(hi_open) {}

Bounds Bounds::any() {
  const double inf = std::numeric_limits<double>::infinity();
  return {-inf, false, inf, false};
}
Bounds Bounds::positive() { return above(0); }
Bounds Bounds::non_negative() { return at_least(0); }
Bounds Bounds::at_least(double lo) {
  return {lo, false, std::numeric_limits<double>::infinity(), false};
}
Bounds Bounds::above(double lo) {
  return {lo, true, std::numeric_limits<double>::infinity(), false};
}
Bounds Bounds::in(double lo, double hi) { return {lo, false, hi, false}; }
Bounds Bounds::in_closed_open(double lo, double hi) { return {lo, false, hi, true}; }
Bounds Bounds::in_open_closed(double lo, double hi) { return {lo, true, hi, false}; }

bool Bounds::contains(double v) const {
  return (lo_open_ ? v > lo_ : v >= lo_) && (hi_open_ ? v < hi_ : v <= hi_);
}

namespace {

// Shortest text of a bound: integers without exponent (1000000, not 1e+06), others round-trip.
std::string bound_text(double x) {
  if (x == std::floor(x) && std::abs(x) < 1e15) return std::to_string(static_cast<long long>(x));
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

}  // namespace

std::string Bounds::to_string() const {
  if (!declared_) return "not declared";
  const bool has_lo = std::isfinite(lo_), has_hi = std::isfinite(hi_);
  if (!has_lo && !has_hi) return "any finite value";
  if (!has_hi) return (lo_open_ ? "> " : ">= ") + bound_text(lo_);
  if (!has_lo) return (hi_open_ ? "< " : "<= ") + bound_text(hi_);
  return std::string("in ") + (lo_open_ ? "(" : "[") + bound_text(lo_) + ", " + bound_text(hi_) +
         (hi_open_ ? ")" : "]");
}

std::string join(const std::vector<std::string>& items, const std::string& sep) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i) out += sep;
    out += items[i];
  }
  return out;
}

std::vector<std::string> closest_names(const std::string& name,
                                       const std::vector<std::string>& known) {
  // Levenshtein distance (insert, delete, substitute), case-insensitive.
  auto lower = [](char c) { return static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c); };
  auto distance = [&](const std::string& a, const std::string& b) {
    std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      cur[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j)
        cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1,
                           prev[j - 1] + (lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1)});
      std::swap(prev, cur);
    }
    return prev[b.size()];
  };
  const std::size_t max_distance = std::max<std::size_t>(2, name.size() / 3);
  std::vector<std::pair<std::size_t, std::string>> scored;
  for (const auto& k : known) {
    const bool prefix =
        name.size() >= 3 && k.size() > name.size() && k.compare(0, name.size(), name) == 0;
    const std::size_t d = prefix ? 1 : distance(name, k);
    if (d <= max_distance && k != name) scored.emplace_back(d, k);
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::string> out;
  for (std::size_t i = 0; i < scored.size() && i < 3; ++i) out.push_back(scored[i].second);
  return out;
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& known) {
  const auto close = closest_names(name, known);
  if (close.empty()) return "";
  std::string s = "; did you mean ";
  for (std::size_t i = 0; i < close.size(); ++i)
    s += (i == 0 ? "" : i + 1 == close.size() ? " or " : ", ") + ("'" + close[i] + "'");
  return s + "?";
}

Params Params::from_assignments(const std::vector<std::string>& assignments) {
  Params p;
  for (const auto& a : assignments) {
    const auto eq = a.find('=');
    require_input(eq != std::string::npos && eq > 0 && eq + 1 < a.size(),
                  "bad --param '" + a + "': expected key=value");
    const std::string key = a.substr(0, eq);
    require_input(!p.contains(key), "--param '" + key + "' given twice");
    p.set(key, a.substr(eq + 1));
  }
  return p;
}

void Params::set(const std::string& key, const std::string& value) { values_[key] = value; }

ParamValue::ParamValue(double v) {
  // 17 significant digits round-trip every double through from_chars (the reader below).
  char buf[32];
  const int n = std::snprintf(buf, sizeof buf, "%.17g", v);
  text_.assign(buf, static_cast<std::size_t>(n));
}

const std::string& Params::raw(const std::string& key) const {
  const auto it = values_.find(key);
  if (it == values_.end()) throw std::logic_error("parameter '" + key + "' read but not declared");
  read_.insert(key);
  return it->second;
}

namespace {

double parse_real(const std::string& key, const std::string& s) {
  double v = 0;
  const auto* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, v);
  require_input(ec == std::errc() && ptr == end,
                "parameter '" + key + "': '" + s + "' is not a number");
  require_input(std::isfinite(v), "parameter '" + key + "': '" + s + "' is not finite");
  return v;
}

long parse_integer(const std::string& key, const std::string& s) {
  long v = 0;
  const auto* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, v);
  require_input(ec == std::errc() && ptr == end,
                "parameter '" + key + "': '" + s + "' is not an integer");
  return v;
}

bool parse_boolean(const std::string& key, const std::string& s) {
  if (s == "true" || s == "1" || s == "yes" || s == "on") return true;
  if (s == "false" || s == "0" || s == "no" || s == "off") return false;
  throw BadInput("parameter '" + key + "': '" + s + "' is not a boolean (true/false)");
}

// BadInput "parameter 'k' = -1 is out of range: must be > 0" unless `bounds` contain `v`.
void check_bounds(const ParamSpec& spec, const std::string& value, double v) {
  require_input(spec.bounds.contains(v), "parameter '" + spec.key + "' = " + value +
                                             " is out of range: must be " +
                                             spec.bounds.to_string());
}

void check_value(const ParamSpec& spec, const std::string& value) {
  switch (spec.type) {
    case ParamType::real:
      check_bounds(spec, value, parse_real(spec.key, value));
      break;
    case ParamType::integer:
      check_bounds(spec, value, static_cast<double>(parse_integer(spec.key, value)));
      break;
    case ParamType::boolean:
      parse_boolean(spec.key, value);
      break;
    case ParamType::text:
      if (!spec.choices.empty()) {
        bool ok = false;
        for (const auto& c : spec.choices) ok = ok || c == value;
        require_input(ok, "parameter '" + spec.key + "': '" + value + "' is not one of " +
                              join(spec.choices, ", "));
      }
      break;
  }
}

}  // namespace

double Params::real(const std::string& key) const { return parse_real(key, raw(key)); }
long Params::integer(const std::string& key) const { return parse_integer(key, raw(key)); }
bool Params::boolean(const std::string& key) const { return parse_boolean(key, raw(key)); }
const std::string& Params::text(const std::string& key) const { return raw(key); }

Params resolve_params(const std::vector<ParamSpec>& specs, const Params& user,
                      std::set<std::string>* consumed, const std::string& owner) {
  Params out;
  for (const auto& spec : specs) {
    std::string value = spec.default_value;
    if (user.contains(spec.key)) {
      value = user.values().at(spec.key);
      if (consumed) consumed->insert(spec.key);
    }
    try {
      check_value(spec, value);
    } catch (const BadInput& e) {
      throw BadInput(std::string(e.what()) + " (" + owner + ")");
    }
    out.set(spec.key, value);
  }
  return out;
}

void check_all_consumed(const Params& user, const std::set<std::string>& consumed,
                        const std::string& accepted_summary,
                        const std::vector<std::string>& known_keys) {
  for (const auto& [key, value] : user.values()) {
    if (!consumed.count(key)) {
      throw BadInput("unknown parameter '" + key + "'" + did_you_mean(key, known_keys) + " (" +
                     accepted_summary + ")");
    }
  }
}

}  // namespace stiffbench

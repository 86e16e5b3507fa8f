#include "integrators/method_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>

#include <toml++/toml.h>

#include "core/params.hpp"
#include "core/theory/additive_conditions.hpp"
#include "core/theory/method_analysis.hpp"
#include "core/types.hpp"
#include "integrators/adaptive/controller.hpp"
#include "integrators/adaptive/embedded_rk.hpp"
#include "integrators/coefficient_expr.hpp"
#include "integrators/embedded_methods.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/imex/imex_ark.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/implicit/gauss.hpp"
#include "integrators/implicit/radau5.hpp"
#include "integrators/solvers/newton.hpp"
#include "integrators/symplectic/composition.hpp"

namespace stiffbench {

static_assert(static_cast<std::size_t>(MethodKind::imex_ark) + 1 == kMethodKindNames.size(),
              "kMethodKindNames lists every MethodKind in its order");

std::string to_string(MethodKind k) {
  const auto i = static_cast<std::size_t>(k);  // kMethodKindNames is in MethodKind's order
  return i < kMethodKindNames.size() ? std::string(kMethodKindNames[i]) : "?";
}

bool MethodDefinition::adaptive() const {
  switch (kind) {
    case MethodKind::explicit_rk:
      return tableau.b_embedded.size() != 0;
    case MethodKind::dirk:
      return tableau.b_embedded.size() != 0 && tableau.stages() > 0 && tableau.a(0, 0) == 0.0;
    case MethodKind::irk:
      return solver == "radau5";
    case MethodKind::rosenbrock:
      return rosenbrock.b_embedded.size() != 0;
    case MethodKind::kick_drift:
      return false;
    case MethodKind::imex_ark:
      return additive.has_embedded();
  }
  return false;
}

namespace {

const std::vector<std::pair<std::string, MethodKind>> kKinds = [] {
  std::vector<std::pair<std::string, MethodKind>> kinds;
  for (std::size_t i = 0; i < kMethodKindNames.size(); ++i)
    kinds.emplace_back(kMethodKindNames[i], static_cast<MethodKind>(i));
  return kinds;
}();

const std::vector<std::string> kCommonKeys = {"name",      "kind",  "order",    "description",
                                              "reference", "class", "constants"};

std::vector<std::string> kind_keys(MethodKind k) {
  switch (k) {
    case MethodKind::explicit_rk:
    case MethodKind::dirk:
      return {"stage_order", "A", "b", "c", "b_embedded", "embedded_order", "fsal"};
    case MethodKind::irk:
      return {"stage_order", "A", "b", "c", "solver"};
    case MethodKind::rosenbrock:
      return {"convention", "gamma",          "alpha", "gamma_offdiag", "b",
              "b_embedded", "embedded_order", "a",     "c_transformed", "m",
              "m_embedded", "w_order"};
    case MethodKind::kick_drift:
      return {"kick", "drift", "composition", "velocity_independent"};
    case MethodKind::imex_ark:
      return {"stage_order", "c", "embedded_order", "explicit", "implicit"};
  }
  return {};
}

// The top-level keys of a file of kind k (the common ones, [constants] aside, and the kind's).
std::vector<std::string> top_level_keys(MethodKind k) {
  std::vector<std::string> keys;
  for (const auto& key : kCommonKeys)
    if (key != "constants") keys.push_back(key);
  for (auto& key : kind_keys(k)) keys.push_back(std::move(key));
  return keys;
}

// The kinds whose top-level keys include `key`.
std::vector<std::string> kinds_with_key(const std::string& key) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < kMethodKindNames.size(); ++i) {
    const auto keys = top_level_keys(static_cast<MethodKind>(i));
    if (std::find(keys.begin(), keys.end(), key) != keys.end())
      out.emplace_back(kMethodKindNames[i]);
  }
  return out;
}

constexpr const char* kTomlTables =
    "(TOML puts every key after a [table] header into that table, up to the next header)";

std::string num(long double x) {
  std::ostringstream os;
  os.precision(6);
  os << static_cast<double>(x);
  return os.str();
}

// Reads one file's keys with their positions for messages.
class Reader {
 public:
  Reader(const toml::table& root, std::string origin) : root_(root), origin_(std::move(origin)) {}

  const std::string& origin() const { return origin_; }

  // A reader of the sub-table [name] (its keys named "name.key" in messages), with the file's
  // constants.
  Reader section(const toml::table& t, const std::string& name) const {
    Reader r(t, origin_);
    r.constants_ = constants_;
    r.prefix_ = name + ".";
    return r;
  }

  std::string where(const toml::node& n) const {
    const auto& s = n.source();
    if (!s.begin) return origin_;
    return origin_ + ":" + std::to_string(s.begin.line);
  }
  std::string where(const std::string& key) const {
    const toml::node* n = root_.get(key);
    return n ? where(*n) : origin_;
  }
  [[noreturn]] void fail(const toml::node& n, const std::string& key,
                         const std::string& what) const {
    const auto l = prefix_.empty() ? lifted_.find(key) : lifted_.end();
    throw BadInput(where(n) + ": key '" + prefix_ + key + "': " + what +
                   (l == lifted_.end() ? std::string()
                                       : " (written inside the table [" + l->second +
                                             "], read as the method's top-level key" +
                                             (l->second == "constants"
                                                  ? ": the format's keys cannot name constants)"
                                                  : ")")));
  }

  const toml::node* get(const std::string& key) const { return root_.get(key); }
  bool has(const std::string& key) const { return root_.contains(key); }

  std::string text(const std::string& key, bool required, const std::string& fallback = "") const {
    const toml::node* n = get(key);
    if (!n) {
      if (required) throw BadInput(origin_ + ": key '" + prefix_ + key + "' missing (a string)");
      return fallback;
    }
    if (!n->is_string()) fail(*n, key, "expected a string");
    const std::string& v = n->as_string()->get();
    // Text fields are printed (list, describe, tables): a control character could act on the
    // terminal there.
    for (std::size_t i = 0; i < v.size(); ++i)
      if (const auto c = static_cast<unsigned char>(v[i]); c < 0x20 || c == 0x7f)
        fail(*n, key,
             "holds a control character (code " + std::to_string(c) + " at character " +
                 std::to_string(i + 1) + "); text fields take printable characters");
    return v;
  }

  int integer(const std::string& key, bool required, int fallback, int lo, int hi) const {
    const toml::node* n = get(key);
    if (!n) {
      if (required) throw BadInput(origin_ + ": key '" + prefix_ + key + "' missing (an integer)");
      return fallback;
    }
    if (!n->is_integer()) fail(*n, key, "expected an integer");
    const auto v = n->as_integer()->get();
    if (v < lo || v > hi)
      fail(*n, key,
           std::to_string(v) + " is outside " + std::to_string(lo) + ".." + std::to_string(hi));
    return static_cast<int>(v);
  }

  bool boolean(const std::string& key, bool fallback) const {
    const toml::node* n = get(key);
    if (!n) return fallback;
    if (!n->is_boolean()) fail(*n, key, "expected true or false");
    return n->as_boolean()->get();
  }

  // A coefficient: a TOML number or a string holding an expression.
  long double coefficient(const toml::node& n, const std::string& key) const {
    if (const auto* i = n.as_integer()) return static_cast<long double>(i->get());
    if (const auto* f = n.as_floating_point()) {
      if (!std::isfinite(f->get())) fail(n, key, "a coefficient is not finite");
      return static_cast<long double>(f->get());
    }
    if (const auto* s = n.as_string()) {
      try {
        return evaluate_coefficient(s->get(), constants_);
      } catch (const BadInput& e) {
        fail(n, key, e.what());
      }
    }
    fail(n, key, "expected a number or a string holding an expression such as \"1/3\"");
  }

  long double scalar(const std::string& key) const {
    const toml::node* n = get(key);
    if (!n) throw BadInput(origin_ + ": key '" + prefix_ + key + "' missing (a coefficient)");
    return coefficient(*n, key);
  }

  // A list of coefficients; empty when absent and not required.
  std::vector<long double> vector(const std::string& key, bool required) const {
    const toml::node* n = get(key);
    if (!n) {
      if (required)
        throw BadInput(origin_ + ": key '" + prefix_ + key + "' missing (a list of coefficients)");
      return {};
    }
    const toml::array* a = n->as_array();
    if (!a) fail(*n, key, "expected a list of coefficients");
    if (a->empty()) fail(*n, key, "the list is empty");
    std::vector<long double> v;
    for (const toml::node& e : *a) v.push_back(coefficient(e, key));
    return v;
  }

  // An s×s matrix given as a list of s rows of s coefficients.
  std::vector<std::vector<long double>> matrix(const std::string& key, std::size_t s) const {
    const toml::node* n = get(key);
    if (!n)
      throw BadInput(origin_ + ": key '" + prefix_ + key + "' missing (" + std::to_string(s) +
                     " rows of " + std::to_string(s) + " coefficients)");
    const toml::array* a = n->as_array();
    if (!a) fail(*n, key, "expected a list of rows (lists of coefficients)");
    if (a->size() != s)
      fail(*n, key,
           std::to_string(a->size()) + " rows, need " + std::to_string(s) +
               " (one per stage; the weights have " + std::to_string(s) + " entries)");
    std::vector<std::vector<long double>> m;
    for (std::size_t i = 0; i < s; ++i) {
      const toml::node& rn = *a->get(i);
      const toml::array* row = rn.as_array();
      if (!row) fail(rn, key, "row " + std::to_string(i + 1) + " is not a list of coefficients");
      if (row->size() != s)
        fail(rn, key,
             "row " + std::to_string(i + 1) + " has " + std::to_string(row->size()) +
                 " entries, need " + std::to_string(s));
      m.emplace_back();
      for (const toml::node& e : *row) m.back().push_back(coefficient(e, key));
    }
    return m;
  }

  // The node of matrix entry (i, j) (for messages).
  const toml::node& entry(const std::string& key, std::size_t i, std::size_t j) const {
    return *get(key)->as_array()->get(i)->as_array()->get(j);
  }
  const toml::node& element(const std::string& key, std::size_t i) const {
    return *get(key)->as_array()->get(i);
  }

  // Entries above the diagonal (strict = false) or on and above it (strict = true) must be 0.
  void require_lower(const std::string& key, const std::vector<std::vector<long double>>& m,
                     bool strict, const std::string& why) const {
    for (std::size_t i = 0; i < m.size(); ++i)
      for (std::size_t j = strict ? i : i + 1; j < m.size(); ++j)
        if (m[i][j] != 0.0L)
          fail(entry(key, i, j), key,
               why + " needs " + key +
                   (strict ? " strictly lower triangular" : " lower triangular") + ": entry (row " +
                   std::to_string(i + 1) + ", column " + std::to_string(j + 1) + ") is " +
                   num(m[i][j]) + ", not 0");
  }

  // [constants]: evaluated in file order, each may use the earlier ones.
  void read_constants() {
    const toml::node* n = get("constants");
    if (!n) return;
    const toml::table* t = n->as_table();
    if (!t) fail(*n, "constants", "expected a table of name = coefficient");
    std::vector<std::pair<toml::source_position, std::string>> order;
    for (const auto& [k, v] : *t) order.emplace_back(v.source().begin, std::string(k.str()));
    std::sort(order.begin(), order.end(), [](const auto& x, const auto& y) {
      return x.first.line != y.first.line ? x.first.line < y.first.line
                                          : x.first.column < y.first.column;
    });
    for (const auto& entry : order) {
      const std::string& k = entry.second;  // a named reference: lambdas below capture it
      const toml::node& v = *t->get(k);
      // A value that is no coefficient, or a key of the format (of another kind: the file's own
      // kind's keys were taken as top-level keys by lift_misplaced_keys) whose value does not
      // evaluate: likely a method key written after the header. The message says so (with the
      // expression's own error, in case a constant was meant).
      const std::vector<std::string> kinds = kinds_with_key(k);
      const auto misplaced = [&](const std::string& detail) {
        throw BadInput(where(v) + ": key '" + k + "' is inside the table [constants] " +
                       kTomlTables + ", but " +
                       (kinds.empty() ? std::string("a constant is a number or a string holding "
                                                    "an expression")
                                      : "'" + k + "' is a method-file key (of kind " + join(kinds) +
                                            "), not a constant") +
                       detail +
                       ": write the method's keys before the [constants] header, or move the "
                       "[constants] table to the end of the file");
      };
      if (!v.is_number() && !v.is_string()) misplaced("");
      if (!kinds.empty() && v.is_string()) try {
          (void)evaluate_coefficient(v.as_string()->get(), constants_);
        } catch (const BadInput& e) {
          misplaced(" (as a constant: " + std::string(e.what()) + ")");
        }
      bool ok = !k.empty() && (std::isalpha(static_cast<unsigned char>(k[0])) || k[0] == '_');
      for (char ch : k) ok = ok && (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_');
      if (!ok || k == "sqrt" || k == "cbrt")
        fail(v, "constants." + k, "a constant's name must be an identifier other than sqrt, cbrt");
      constants_[k] = coefficient(v, "constants." + k);
    }
  }

 private:
  const toml::table& root_;
  std::string origin_;
  CoefficientConstants constants_;
  std::string prefix_;  // "explicit." in a section's reader

 public:
  // Top-level keys found inside a table (lift_misplaced_keys), by the table's name: messages
  // about them say so.
  std::map<std::string, std::string> lifted_;
};

Vec to_vec(const std::vector<long double>& v) {
  Vec out(static_cast<Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) out[static_cast<Index>(i)] = static_cast<double>(v[i]);
  return out;
}

Mat to_mat(const std::vector<std::vector<long double>>& m) {
  const auto s = static_cast<Index>(m.size());
  Mat out(s, s);
  for (Index i = 0; i < s; ++i)
    for (Index j = 0; j < s; ++j)
      out(i, j) = static_cast<double>(m[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)]);
  return out;
}

std::string shape_text(MethodKind k) {
  return k == MethodKind::explicit_rk ? "an explicit_rk method"
         : k == MethodKind::dirk      ? "a dirk method"
                                      : "this method";
}

// The key a tableau's validate() message is about, for its line.
std::string key_of_defect(const std::string& message) {
  if (message.find("embedded") != std::string::npos) return "embedded_order";
  if (message.find("stage order") != std::string::npos) return "stage_order";
  if (message.find("fsal") != std::string::npos) return "fsal";
  if (message.find("order") != std::string::npos) return "order";
  return "A";
}

// explicit_rk, dirk, irk: A, b, c, b_embedded, embedded_order, fsal, stage_order.
void read_runge_kutta(const Reader& r, MethodDefinition& m) {
  const std::vector<long double> b = r.vector("b", true);
  const std::size_t s = b.size();
  const auto a = r.matrix("A", s);
  if (m.kind == MethodKind::explicit_rk) r.require_lower("A", a, true, "an explicit_rk method");
  if (m.kind == MethodKind::dirk) r.require_lower("A", a, false, "a dirk method");
  ButcherTableau& t = m.tableau;
  t.name = m.name;
  t.order = m.order;
  t.a = to_mat(a);
  t.b = to_vec(b);
  const std::vector<long double> c = r.vector("c", m.kind == MethodKind::irk);
  if (!c.empty()) {
    if (c.size() != s)
      r.fail(*r.get("c"), "c", std::to_string(c.size()) + " entries, need " + std::to_string(s));
    for (std::size_t i = 0; i < s; ++i) {
      long double sum = 0;
      for (long double x : a[i]) sum += x;
      if (std::fabs(c[i] - sum) > 1e-12L * std::max(1.0L, std::fabs(sum)))
        r.fail(r.element("c", i), "c",
               "c[" + std::to_string(i + 1) + "] = " + num(c[i]) + " is not the row sum of A (" +
                   num(sum) + ")");
    }
    t.c = to_vec(c);
  }
  if (m.kind != MethodKind::irk) {
    const std::vector<long double> be = r.vector("b_embedded", false);
    if (!be.empty() && be.size() != s)
      r.fail(*r.get("b_embedded"), "b_embedded",
             std::to_string(be.size()) + " entries, need " + std::to_string(s));
    if (!be.empty() && !r.has("embedded_order"))
      throw BadInput(r.where("b_embedded") + ": key 'b_embedded' given without 'embedded_order'");
    if (be.empty() && r.has("embedded_order"))
      throw BadInput(r.where("embedded_order") +
                     ": key 'embedded_order' given without 'b_embedded'");
    t.b_embedded = to_vec(be);
    t.embedded_order = r.integer("embedded_order", false, 0, 1, 12);
    t.fsal = r.boolean("fsal", false);
  } else {
    m.solver = r.text("solver", false);
    if (!m.solver.empty() && m.solver != "radau5")
      r.fail(*r.get("solver"), "solver",
             "unknown solver '" + m.solver + "'; known: radau5 (or leave it out)");
    if (m.solver == "radau5" && s != 3)
      r.fail(*r.get("solver"), "solver",
             "radau5 runs 3-stage tableaux (Radau IIA); this one has " + std::to_string(s));
    const Eigen::FullPivLU<Mat> lu(t.a);
    if (!lu.isInvertible())
      throw BadInput(r.where("A") +
                     ": key 'A': an irk method needs an invertible A (its simplified Newton "
                     "iteration works with A's inverse); this A is singular");
  }
  t.stage_order = r.integer("stage_order", false, 0, 1, 12);
  const ButcherTableau::Shape shape =
      m.kind == MethodKind::explicit_rk ? ButcherTableau::Shape::explicit_rk
      : m.kind == MethodKind::dirk      ? ButcherTableau::Shape::diagonally_implicit
                                        : ButcherTableau::Shape::any;
  try {
    t.validate(shape);
  } catch (const BadInput& e) {
    const std::string key = key_of_defect(e.what());
    throw BadInput(r.where(key) + ": key '" + key + "': " + e.what() + " (" + shape_text(m.kind) +
                   ")");
  }
}

// The first condition a claim of `order` violates (lowest order first, up to order 8), as a
// message; empty when every condition holds (core/theory/method_analysis.hpp).
std::string violated_claim(const std::vector<OrderCondition>& conditions, int order,
                           const std::string& what) {
  const auto v = first_violated_condition(conditions, std::min(order, 8));
  if (!v) return {};
  return what + " " + std::to_string(order) + " claimed but " +
         (v->tree >= 0 ? "the condition of tree " + v->name : "the " + v->name) + " (order " +
         std::to_string(v->order) + ") has residual " + num(v->residual);
}

void read_rosenbrock(const Reader& r, MethodDefinition& m) {
  const std::string convention = r.text("convention", false, "hairer_wanner");
  if (convention != "hairer_wanner" && convention != "transformed")
    r.fail(*r.get("convention"), "convention",
           "unknown convention '" + convention +
               "'; known: hairer_wanner (alpha, gamma_offdiag, b; the default), transformed (a, "
               "c_transformed, m)");
  const bool transformed = convention == "transformed";
  for (const char* key : transformed
                             ? std::vector<const char*>{"alpha", "gamma_offdiag", "b", "b_embedded"}
                             : std::vector<const char*>{"a", "c_transformed", "m", "m_embedded"})
    if (r.has(key))
      r.fail(*r.get(key), key,
             std::string("not a key of convention '") + convention + "' (" +
                 (transformed ? "a, c_transformed, m, m_embedded"
                              : "alpha, gamma_offdiag, b, b_embedded") +
                 ")");
  const long double gamma = r.scalar("gamma");
  if (!(gamma > 0.0L)) r.fail(*r.get("gamma"), "gamma", "must be positive, not " + num(gamma));
  const std::string w = transformed ? "m" : "b", we = transformed ? "m_embedded" : "b_embedded";
  const std::string ma = transformed ? "a" : "alpha",
                    mg = transformed ? "c_transformed" : "gamma_offdiag";
  const std::vector<long double> b = r.vector(w, true);
  const std::size_t s = b.size();
  const auto alpha = r.matrix(ma, s);
  const auto goff = r.matrix(mg, s);
  r.require_lower(ma, alpha, true, "a Rosenbrock method");
  r.require_lower(mg, goff, true, "a Rosenbrock method");
  const std::vector<long double> be = r.vector(we, false);
  if (!be.empty() && be.size() != s)
    r.fail(*r.get(we), we, std::to_string(be.size()) + " entries, need " + std::to_string(s));
  if (!be.empty() && !r.has("embedded_order"))
    throw BadInput(r.where(we) + ": key '" + we + "' given without 'embedded_order'");
  if (be.empty() && r.has("embedded_order"))
    throw BadInput(r.where("embedded_order") + ": key 'embedded_order' given without '" + we + "'");
  const int embedded_order = r.integer("embedded_order", false, 0, 1, 12);
  RosenbrockTableau& t = m.rosenbrock;
  if (transformed) {
    t = rosenbrock_from_transformed(m.name, m.order, embedded_order, static_cast<double>(gamma),
                                    to_mat(alpha), to_mat(goff), to_vec(b), to_vec(be));
  } else {
    t.name = m.name;
    t.order = m.order;
    t.gamma = static_cast<double>(gamma);
    t.alpha = to_mat(alpha);
    t.gamma_lower = to_mat(goff);
    t.b = to_vec(b);
    t.b_embedded = to_vec(be);
    t.embedded_order = embedded_order;
  }
  if (!t.alpha.allFinite() || !t.gamma_lower.allFinite() || !t.b.allFinite() ||
      !t.b_embedded.allFinite())
    throw BadInput(r.where(ma) + ": a coefficient is not finite");
  // The order conditions of Hairer & Wanner II, §IV.7, by rooted trees up to order 8.
  const std::string who = "Rosenbrock method '" + m.name + "': ";
  if (const std::string d = violated_claim(analyze_rosenbrock(t).conditions, m.order, "order");
      !d.empty())
    throw BadInput(r.where("order") + ": key 'order': " + who + d);
  if (t.b_embedded.size() != 0) {
    RosenbrockTableau embedded = t;
    embedded.b = t.b_embedded;
    if (const std::string d = violated_claim(analyze_rosenbrock(embedded).conditions,
                                             embedded_order, "embedded order");
        !d.empty())
      throw BadInput(r.where("embedded_order") + ": key 'embedded_order': " + who + d);
  }
  // The W-conditions (an arbitrary matrix in place of J; core/theory/method_analysis.hpp), up to
  // the claim, which cannot exceed the classical order.
  t.w_order = r.integer("w_order", false, 0, 1, kMaxWOrder);
  if (t.w_order > m.order)
    r.fail(*r.get("w_order"), "w_order",
           "W-order " + std::to_string(t.w_order) + " claimed above the order " +
               std::to_string(m.order) + " (the W-conditions include the classical ones)");
  if (t.w_order > 0)
    if (const auto v =
            first_violated_condition(rosenbrock_w_conditions(t, t.b, t.w_order), t.w_order))
      throw BadInput(r.where("w_order") + ": key 'w_order': " + who + "W-order " +
                     std::to_string(t.w_order) + " claimed but the W-condition of tree " + v->name +
                     " (order " + std::to_string(v->order) + ") has residual " + num(v->residual));
}

std::vector<double> to_doubles(const std::vector<long double>& v) {
  return std::vector<double>(v.begin(), v.end());
}

void read_kick_drift(const Reader& r, MethodDefinition& m) {
  const bool composition = r.has("composition");
  if (composition && (r.has("kick") || r.has("drift")))
    r.fail(*r.get("composition"), "composition",
           "give either composition (Verlet substeps) or kick and drift, not both");
  KickDriftCoefficients& c = m.splitting.kick_drift;
  if (composition) {
    const std::vector<long double> g = r.vector("composition", true);
    c = verlet_composition(m.name, to_doubles(g), m.order);
  } else {
    const std::vector<long double> kick = r.vector("kick", true);
    const std::vector<long double> drift = r.vector("drift", true);
    if (kick.size() != drift.size())
      r.fail(*r.get("drift"), "drift",
             std::to_string(drift.size()) + " entries, kick has " + std::to_string(kick.size()));
    c.name = m.name;
    c.kick = to_doubles(kick);
    c.drift = to_doubles(drift);
    c.order = m.order;
  }
  m.splitting.velocity_independent = r.boolean("velocity_independent", true);
  // The conditions of the free Lie algebra up to degree 8 (core/theory/method_analysis.hpp,
  // analyze_kick_drift: for x'' = a(x), without the terms that vanish there).
  if (const std::string d = violated_claim(analyze_kick_drift(c).conditions, m.order, "order");
      !d.empty())
    throw BadInput(r.where("order") + ": key 'order': kick/drift method '" + m.name + "': " + d +
                   (m.order >= 1 && c.order_defect(1) > 1e-12
                        ? " (the kicks and the drifts must each sum to 1)"
                        : ""));
}

// imex_ark: the [explicit] and [implicit] sections of an additive Runge–Kutta method.
const toml::table& imex_section(const Reader& r, const std::string& name) {
  const toml::node* n = r.get(name);
  if (!n)
    throw BadInput(r.origin() + ": section [" + name +
                   "] missing (A, b and optionally b_embedded " + "and c of the " + name +
                   " table)");
  const toml::table* t = n->as_table();
  if (!t) r.fail(*n, name, "expected a section [" + name + "] with A, b (and b_embedded, c)");
  const std::vector<std::string> known = {"A", "b", "b_embedded", "c"};
  for (const auto& [k, v] : *t) {
    const std::string key(k.str());
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      if (!kinds_with_key(key).empty())
        throw BadInput(r.where(v) + ": key '" + key + "' is inside the table [" + name + "] " +
                       kTomlTables + ", but it is not a key of the " + name +
                       " table (A, b, b_embedded, c) nor a top-level key of kind 'imex_ark': " +
                       "write the top-level keys before the first [table] header");
      throw BadInput(r.where(v) + ": unknown key '" + name + "." + key + "' in section [" + name +
                     "]" + did_you_mean(key, known) + "; known: " + join(known));
    }
  }
  return *t;
}

// c[i] must be the row sum of A (1e-12, as for the other kinds).
void check_nodes(const Reader& owner, const std::string& key, const std::vector<long double>& c,
                 const std::vector<std::vector<long double>>& a, const std::string& table) {
  if (c.size() != a.size())
    owner.fail(*owner.get("c"), key,
               std::to_string(c.size()) + " entries, need " + std::to_string(a.size()));
  for (std::size_t i = 0; i < c.size(); ++i) {
    long double sum = 0;
    for (long double x : a[i]) sum += x;
    if (std::fabs(c[i] - sum) > 1e-12L * std::max(1.0L, std::fabs(sum)))
      owner.fail(owner.element("c", i), key,
                 "c[" + std::to_string(i + 1) + "] = " + num(c[i]) + " is not the row sum of the " +
                     table + " table's A (" + num(sum) + ")");
  }
}

// One table: A (shape checked), b, b_embedded, its nodes (own c, else the shared c, else the
// row sums).
ButcherTableau read_imex_table(const Reader& r, const Reader& sec, const std::string& name,
                               std::size_t stages, const std::vector<long double>& shared_c) {
  const std::vector<long double> b = sec.vector("b", true);
  if (stages != 0 && b.size() != stages)
    sec.fail(*sec.get("b"), "b",
             std::to_string(b.size()) + " entries, the explicit table has " +
                 std::to_string(stages) + " stages");
  const auto a = sec.matrix("A", b.size());
  sec.require_lower("A", a, name == "explicit", "the " + name + " table of an imex_ark method");
  const std::vector<long double> be = sec.vector("b_embedded", false);
  if (!be.empty() && be.size() != b.size())
    sec.fail(*sec.get("b_embedded"), "b_embedded",
             std::to_string(be.size()) + " entries, need " + std::to_string(b.size()));
  std::vector<long double> c = sec.vector("c", false);
  if (!c.empty() && !shared_c.empty())
    sec.fail(*sec.get("c"), "c",
             "give the nodes either once at the top (shared) or in each section, not both");
  if (!c.empty()) {
    check_nodes(sec, "c", c, a, name);
  } else if (!shared_c.empty()) {
    check_nodes(r, "c", shared_c, a, name);
    c = shared_c;
  } else {
    for (const auto& row : a) {
      long double sum = 0;
      for (long double x : row) sum += x;
      c.push_back(sum);
    }
  }
  ButcherTableau t;
  t.name = r.origin() + " (" + name + " table)";
  t.a = to_mat(a);
  t.b = to_vec(b);
  t.c = to_vec(c);
  t.b_embedded = to_vec(be);
  return t;
}

void read_imex_ark(const Reader& r, MethodDefinition& m) {
  const Reader ex = r.section(imex_section(r, "explicit"), "explicit");
  const Reader im = r.section(imex_section(r, "implicit"), "implicit");
  const std::vector<long double> shared_c = r.vector("c", false);
  AdditiveTableau& t = m.additive;
  t.name = m.name;
  t.order = m.order;
  t.explicit_table = read_imex_table(r, ex, "explicit", 0, shared_c);
  t.implicit_table = read_imex_table(r, im, "implicit", t.explicit_table.b.size(), shared_c);
  t.explicit_table.name = m.name + " (explicit table)";
  t.implicit_table.name = m.name + " (implicit table)";
  const bool emb_e = t.explicit_table.b_embedded.size() != 0;
  const bool emb_i = t.implicit_table.b_embedded.size() != 0;
  if (emb_e != emb_i)
    throw BadInput((emb_e ? ex.where("b_embedded") : im.where("b_embedded")) + ": key '" +
                   (emb_e ? "explicit" : "implicit") +
                   ".b_embedded': give the embedded weights of both tables or of neither");
  if (emb_e && !r.has("embedded_order"))
    throw BadInput(ex.where("b_embedded") +
                   ": key 'explicit.b_embedded' given without 'embedded_order'");
  if (!emb_e && r.has("embedded_order"))
    throw BadInput(r.where("embedded_order") +
                   ": key 'embedded_order' given without the tables' b_embedded");
  t.embedded_order = r.integer("embedded_order", false, 0, 1, 12);
  const std::string who = "imex_ark method '" + m.name + "': ";
  // Each table alone (rooted trees up to order 8), then the pair's coupling conditions.
  for (ButcherTableau* tab : {&t.explicit_table, &t.implicit_table}) {
    const std::string part = tab == &t.explicit_table ? "explicit" : "implicit";
    if (const std::string d =
            violated_claim(rk_order_conditions(*tab, tab->b, std::min(m.order, 8)), m.order,
                           "the " + part + " table alone: order");
        !d.empty())
      throw BadInput(r.where("order") + ": key 'order': " + who + d);
    if (emb_e) {
      if (const std::string d = violated_claim(
              rk_order_conditions(*tab, tab->b_embedded, std::min(t.embedded_order, 8)),
              t.embedded_order, "the " + part + " table's embedded weights alone: embedded order");
          !d.empty())
        throw BadInput(r.where("embedded_order") + ": key 'embedded_order': " + who + d);
    }
    tab->order = tab->satisfied_order(1e-12, 6);
    tab->embedded_order = emb_e ? tab->satisfied_order(tab->b_embedded, 1e-12, 6) : 0;
  }
  const auto coupling = [&](const Vec& we, const Vec& wi, int order, const std::string& label,
                            const std::string& key) {
    const int p = std::min(order, 4);
    const auto conditions =
        additive_order_conditions(t.explicit_table, t.implicit_table, we, wi, p, label);
    if (const auto v = first_violated_additive_condition(conditions, p, true))
      throw BadInput(r.where(key) + ": key '" + key + "': " + who + key + " " +
                     std::to_string(order) + " claimed but the coupling condition " + v->name +
                     " (order " + std::to_string(v->order) + ") has residual " + num(v->residual));
  };
  coupling(t.explicit_table.b, t.implicit_table.b, m.order, "b", "order");
  if (emb_e)
    coupling(t.explicit_table.b_embedded, t.implicit_table.b_embedded, t.embedded_order,
             "b_embedded_", "embedded_order");
  const int q = r.integer("stage_order", false, 0, 1, 12);
  if (q > 0 && t.implicit_table.satisfied_stage_order() < q)
    throw BadInput(r.where("stage_order") + ": key 'stage_order': " + who + "stage order " +
                   std::to_string(q) + " claimed but the implicit table meets C(" +
                   std::to_string(t.implicit_table.satisfied_stage_order()) + ") only");
  t.implicit_table.stage_order = q;
}

std::string default_class(const MethodDefinition& m) {
  switch (m.kind) {
    case MethodKind::explicit_rk:
      return m.adaptive() ? "embedded RK pair" : "explicit RK";
    case MethodKind::dirk: {
      const std::string base = m.tableau.a(0, 0) == 0.0 ? "ESDIRK" : "SDIRK";
      return m.tableau.b_embedded.size() != 0 ? base + " (embedded pair)" : base;
    }
    case MethodKind::irk:
      return m.solver == "radau5" ? "Radau IIA (RADAU5)" : "implicit RK";
    case MethodKind::rosenbrock:
      return m.rosenbrock.b_embedded.size() != 0 ? "Rosenbrock (embedded pair)" : "Rosenbrock";
    case MethodKind::kick_drift:
      return "splitting";
    case MethodKind::imex_ark:
      return m.additive.has_embedded() ? "IMEX additive RK (embedded pair)" : "IMEX additive RK";
  }
  return "";
}

// A file that starts with its [constants] table (define γ, then use it) has, by TOML's rule,
// every key after the header inside that table; likewise a key written after an imex_ark
// method's [explicit] or [implicit] section. The file's top-level keys of its kind found in such
// a table, where they cannot mean anything else (a constant cannot take a key's name; a section
// has only A, b, b_embedded and c), are taken as the top-level keys they are. A key both there
// and at the top level is an error naming both lines. The kind itself is looked for at the top
// level first, then in those tables.
std::map<std::string, std::string> lift_misplaced_keys(toml::table& root,
                                                       const std::string& origin) {
  std::map<std::string, std::string> lifted;
  std::vector<std::string> tables = {"constants", "explicit", "implicit"};
  const toml::node* kind_node = root.get("kind");
  for (const auto& name : tables)
    if (const toml::table* t = root[name].as_table(); !kind_node && t) kind_node = t->get("kind");
  const std::string kind_text(current_method_kind(
      kind_node && kind_node->is_string() ? kind_node->as_string()->get() : std::string()));
  if (kind_text != "imex_ark") tables = {"constants"};  // the sections are imex_ark's only
  std::vector<std::string> keys = {"name", "kind", "order", "description", "reference", "class"};
  for (std::size_t i = 0; i < kMethodKindNames.size(); ++i)
    if (kind_text == kMethodKindNames[i]) keys = top_level_keys(static_cast<MethodKind>(i));
  const auto line = [](const toml::node& n) {
    return n.source().begin ? std::to_string(n.source().begin.line) : std::string("?");
  };
  for (const auto& name : tables) {
    toml::table* t = root[name].as_table();
    if (!t) continue;
    const std::vector<std::string> own =
        name == "constants" ? std::vector<std::string>{}
                            : std::vector<std::string>{"A", "b", "b_embedded", "c"};
    std::vector<std::string> lift;
    for (const auto& [k, v] : *t) {
      const std::string key(k.str());
      if (std::find(keys.begin(), keys.end(), key) == keys.end() ||
          std::find(own.begin(), own.end(), key) != own.end())
        continue;
      if (const toml::node* top = root.get(key))
        throw BadInput(origin + ":" + line(v) + ": key '" + key + "' is inside the table [" + name +
                       "] " + kTomlTables + " and also at the top level (line " + line(*top) +
                       "); '" + key + "' is a method-file key" +
                       (name == "constants" ? ", not a name for a constant" : "") +
                       ": keep one of them");
      lift.push_back(key);
    }
    for (const auto& key : lift) {
      t->get(key)->visit([&](auto& node) { root.insert(key, std::move(node)); });
      t->erase(key);
      lifted[key] = name;
    }
  }
  return lifted;
}

void check_keys(const toml::table& root, const std::string& origin, MethodKind kind) {
  std::vector<std::string> known = kCommonKeys;
  for (auto& k : kind_keys(kind)) known.push_back(k);
  for (const auto& [k, v] : root) {
    const std::string key(k.str());
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      const auto& b = v.source().begin;
      throw BadInput(origin + (b ? ":" + std::to_string(b.line) : std::string()) +
                     ": unknown key '" + key + "' for kind '" + to_string(kind) + "'" +
                     did_you_mean(key, known) + "; known: " + join(known));
    }
  }
}

// Refuses non-ASCII text outside strings and comments before toml++ sees it (toml++ 3.3.0
// reaches undefined behaviour on some such input; see experiments/framework/spec_file.cpp).
void require_ascii_outside_strings(const std::string& text, const std::string& origin) {
  int line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '#') {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
    } else if (c == '"' || c == '\'') {
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
        if (text[j] == '\n') ++line;
        ++j;
      }
      i = std::min(j + close.size(), text.size()) - 1;
    } else if (static_cast<unsigned char>(c) >= 0x80) {
      throw BadInput(origin + ":" + std::to_string(line) +
                     ": non-ASCII character outside a string or comment");
    }
  }
}

std::unique_ptr<Integrator> build(const MethodDefinition& m, const Params& p) {
  switch (m.kind) {
    case MethodKind::explicit_rk:
      if (m.adaptive())
        return std::make_unique<EmbeddedRungeKutta>(m.tableau, m.description,
                                                    read_controller_options(p));
      return std::make_unique<ExplicitRungeKutta>(m.tableau, m.description);
    case MethodKind::dirk:
      if (m.tableau.b_embedded.size() != 0)
        return std::make_unique<DirkIntegrator>(m.tableau, m.description,
                                                read_implicit_options(p, true),
                                                read_controller_options(p), read_error_filter(p));
      return std::make_unique<DirkIntegrator>(m.tableau, m.description,
                                              read_implicit_options(p, true));
    case MethodKind::irk:
      if (m.solver == "radau5") return std::make_unique<Radau5>(m.tableau, read_radau5_options(p));
      return std::make_unique<ImplicitRungeKutta>(m.tableau, m.description, read_gauss_options(p));
    case MethodKind::rosenbrock:
      if (m.adaptive())
        return std::make_unique<Rosenbrock>(m.rosenbrock, m.description,
                                            read_implicit_options(p, false),
                                            read_controller_options(p));
      return std::make_unique<Rosenbrock>(m.rosenbrock, m.description,
                                          read_implicit_options(p, false));
    case MethodKind::kick_drift:
      return std::make_unique<KickDriftIntegrator>(m.splitting.kick_drift,
                                                   m.splitting.velocity_independent, m.description);
    case MethodKind::imex_ark:
      if (m.adaptive())
        return std::make_unique<ImexArkIntegrator>(
            m.additive, m.description, read_implicit_options(p, true), read_controller_options(p),
            read_error_filter(p));
      return std::make_unique<ImexArkIntegrator>(m.additive, m.description,
                                                 read_implicit_options(p, true));
  }
  throw std::logic_error("make_integrator: unknown kind");
}

MethodInfo info_of(const MethodDefinition& m, const Integrator& probe) {
  MethodInfo info = probe.info();
  info.name = m.name;
  info.description = m.description;
  info.kind = m.class_text;
  info.reference = m.reference.empty() ? "not given (" + m.source + ")" : m.reference;
  return info;
}

}  // namespace

MethodDefinition parse_method_file(const std::string& text, const std::string& origin) {
  toml::table root;
  try {
    require_ascii_outside_strings(text, origin);
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& err) {
    const auto& b = err.source().begin;
    throw BadInput(origin + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": " +
                   std::string(err.description()));
  }
  const std::map<std::string, std::string> lifted = lift_misplaced_keys(root, origin);
  Reader r(root, origin);
  r.lifted_ = lifted;
  MethodDefinition m;
  m.source = origin;
  // kick_drift's old name "splitting" still reads, for one version.
  const std::string kind(current_method_kind(r.text("kind", true)));
  const auto it =
      std::find_if(kKinds.begin(), kKinds.end(), [&](const auto& k) { return k.first == kind; });
  if (it == kKinds.end()) {
    std::vector<std::string> known;
    for (const auto& k : kKinds) known.push_back(k.first);
    r.fail(*r.get("kind"), "kind",
           "unknown kind '" + kind + "'" + did_you_mean(kind, known) + "; known: " + join(known));
  }
  m.kind = it->second;
  check_keys(root, origin, m.kind);
  m.name = r.text("name", true);
  {
    bool ok = !m.name.empty();
    for (char c : m.name) ok = ok && ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_');
    if (!ok)
      r.fail(*r.get("name"), "name",
             "'" + m.name + "' is not a method name (lower-case letters, digits and _)");
  }
  m.order = r.integer("order", true, 0, 1, 20);
  m.description = r.text("description", true);
  if (m.description.empty()) r.fail(*r.get("description"), "description", "is empty");
  m.reference = r.text("reference", false);
  r.read_constants();
  switch (m.kind) {
    case MethodKind::explicit_rk:
    case MethodKind::dirk:
    case MethodKind::irk:
      read_runge_kutta(r, m);
      break;
    case MethodKind::rosenbrock:
      read_rosenbrock(r, m);
      break;
    case MethodKind::kick_drift:
      read_kick_drift(r, m);
      break;
    case MethodKind::imex_ark:
      read_imex_ark(r, m);
      break;
  }
  m.class_text = r.text("class", false, default_class(m));
  // The integrator's own checks (its constructor: e.g. A⁻¹ diagonalisable for irk, RADAU5's
  // structure for solver = "radau5"), reported against the file.
  try {
    (void)make_integrator(m);
  } catch (const BadInput& e) {
    throw BadInput(r.where("A") + ": " + e.what());
  }
  return m;
}

MethodDefinition load_method_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw BadInput(path + ": cannot read the method file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_method_file(buffer.str(), path);
}

std::vector<ParamSpec> method_param_specs(const MethodDefinition& m) {
  switch (m.kind) {
    case MethodKind::explicit_rk:
      return m.adaptive() ? controller_param_specs() : std::vector<ParamSpec>{};
    case MethodKind::dirk:
      return m.tableau.b_embedded.size() != 0 ? esdirk_param_specs() : implicit_param_specs(true);
    case MethodKind::irk:
      return m.solver == "radau5" ? radau5_param_specs() : gauss_param_specs();
    case MethodKind::rosenbrock: {
      std::vector<ParamSpec> specs;
      if (m.adaptive()) specs = controller_param_specs();
      for (ParamSpec& s : implicit_param_specs(false)) specs.push_back(std::move(s));
      return specs;
    }
    case MethodKind::kick_drift:
      return {};
    case MethodKind::imex_ark:
      return m.adaptive() ? esdirk_param_specs(false) : implicit_param_specs(true);
  }
  return {};
}

std::unique_ptr<Integrator> make_integrator(const MethodDefinition& m, const Params& p) {
  const Params effective =
      resolve_params(method_param_specs(m), p, nullptr, "integrator '" + m.name + "'");
  return build(m, effective);
}

IntegratorRegistry::Entry method_registry_entry(const MethodDefinition& m) {
  const std::unique_ptr<Integrator> probe = make_integrator(m);
  return {info_of(m, *probe), method_param_specs(m), [m](const Params& p) { return build(m, p); }};
}

const std::vector<MethodDefinition>& built_in_methods() {
  static const std::vector<MethodDefinition> methods = [] {
    std::vector<MethodDefinition> out;
    for (const auto& [file, text] : embedded_method_files()) {
      const std::string origin = "methods/" + std::string(file);
      MethodDefinition m = parse_method_file(std::string(text), origin);
      m.source = origin + " (built in)";
      out.push_back(std::move(m));
    }
    return out;
  }();
  return methods;
}

const MethodDefinition& built_in_method(const std::string& name) {
  for (const MethodDefinition& m : built_in_methods())
    if (m.name == name) return m;
  throw std::logic_error("no built-in method file defines '" + name + "'");
}

}  // namespace stiffbench

#include "core/theory/additive_conditions.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

namespace stiffbench {

namespace {

// A bi-coloured rooted tree: root colour (0 = E, 1 = I) and its subtrees (indices into the
// list being built, non-decreasing, so that each multiset of subtrees occurs once).
struct ColouredTree {
  int order = 1;
  int colour = 0;
  std::vector<int> children;
  long density = 1;
  Vec phi;          // Φ(τ), the stage vector of the elementary weight
  std::string vec;  // Φ as an expression ("1", "c", "AI·c", "c*(AE·c)")
  int colours = 0;  // bit mask of the colours that show in the condition's name
};

const char* colour_name(int colour) { return colour == 0 ? "E" : "I"; }

// The name of A^ν Φ(child) as a factor of an elementwise product, and the colours it shows.
std::string factor_name(const ColouredTree& child, bool shared_nodes, int* colours) {
  if (child.children.empty()) {
    if (shared_nodes) return "c";
    *colours |= 1 << child.colour;
    return std::string("c") + colour_name(child.colour);
  }
  *colours |= (1 << child.colour) | child.colours;
  const bool product = child.vec.find('*') != std::string::npos;
  return std::string("A") + colour_name(child.colour) + "·" +
         (product ? "(" + child.vec + ")" : child.vec);
}

// Elementwise product of the factors, sorted, repeated ones as powers: "c^2*(AI·c)".
std::string product_name(std::vector<std::string> factors) {
  if (factors.empty()) return "1";
  std::sort(factors.begin(), factors.end());
  std::string out;
  for (std::size_t i = 0; i < factors.size();) {
    std::size_t j = i;
    while (j < factors.size() && factors[j] == factors[i]) ++j;
    const bool simple = factors[i].find("·") == std::string::npos;
    std::string f = factors[i];
    if (j - i > 1) {
      f = (simple ? f : "(" + f + ")") + "^" + std::to_string(j - i);
    } else if (!simple && factors.size() > 1) {
      f = "(" + f + ")";
    }
    out += (out.empty() ? "" : "*") + f;
    i = j;
  }
  return out;
}

// Every multiset of trees (indices >= start, non-decreasing) with total order `remaining`.
void multisets(const std::vector<ColouredTree>& trees, std::size_t start, int remaining,
               std::vector<int>& current, std::vector<std::vector<int>>& out) {
  if (remaining == 0) {
    out.push_back(current);
    return;
  }
  for (std::size_t k = start; k < trees.size(); ++k) {
    if (trees[k].order > remaining) continue;
    current.push_back(static_cast<int>(k));
    multisets(trees, k, remaining - trees[k].order, current, out);
    current.pop_back();
  }
}

bool same_nodes(const ButcherTableau& e, const ButcherTableau& i) {
  if (e.c.size() != i.c.size()) return false;
  for (Index k = 0; k < e.c.size(); ++k)
    if (std::abs(e.c[k] - i.c[k]) > 1e-12) return false;
  return true;
}

}  // namespace

std::vector<AdditiveCondition> additive_order_conditions(const ButcherTableau& explicit_table,
                                                         const ButcherTableau& implicit_table,
                                                         const Vec& wE, const Vec& wI,
                                                         int max_order, const std::string& label) {
  if (max_order < 1 || max_order > 6)
    throw std::logic_error("additive_order_conditions: max_order must be 1..6");
  const Index s = explicit_table.stages();
  if (implicit_table.stages() != s || wE.size() != s || wI.size() != s)
    throw std::logic_error("additive_order_conditions: the tables have different sizes");
  const bool shared = same_nodes(explicit_table, implicit_table);
  const Mat* a[2] = {&explicit_table.a, &implicit_table.a};
  const Vec* w[2] = {&wE, &wI};
  std::vector<ColouredTree> trees;
  std::vector<AdditiveCondition> out;
  std::set<std::string> seen;
  for (int n = 1; n <= max_order; ++n) {
    std::vector<std::vector<int>> kids;
    std::vector<int> current;
    multisets(trees, 0, n - 1, current, kids);
    std::vector<ColouredTree> fresh;
    for (int colour = 0; colour < 2; ++colour) {
      for (const std::vector<int>& ch : kids) {
        ColouredTree t;
        t.order = n;
        t.colour = colour;
        t.children = ch;
        t.phi = Vec::Ones(s);
        std::vector<std::string> factors;
        for (int k : ch) {
          const ColouredTree& c = trees[static_cast<std::size_t>(k)];
          t.density *= c.density;
          t.phi = t.phi.cwiseProduct(*a[c.colour] * c.phi);
          factors.push_back(factor_name(c, shared, &t.colours));
        }
        t.density *= n;
        t.vec = product_name(factors);
        const std::string name = std::string(label) + colour_name(colour) + "·" + t.vec + " = 1/" +
                                 std::to_string(t.density);
        const int shown = t.colours | (1 << colour);
        if (seen.insert(name).second)
          out.push_back(
              {n, name, w[colour]->dot(t.phi) - 1.0 / static_cast<double>(t.density), shown == 3});
        fresh.push_back(std::move(t));
      }
    }
    for (ColouredTree& t : fresh) trees.push_back(std::move(t));
  }
  return out;
}

std::optional<AdditiveCondition> first_violated_additive_condition(
    const std::vector<AdditiveCondition>& conditions, int order, bool coupling_only, double tol) {
  for (const AdditiveCondition& c : conditions)
    if (c.order <= order && (c.coupling || !coupling_only) && !(std::abs(c.residual) <= tol))
      return c;
  return std::nullopt;
}

int additive_satisfied_order(const ButcherTableau& explicit_table,
                             const ButcherTableau& implicit_table, const Vec& wE, const Vec& wI,
                             int max_order, double tol) {
  const auto conditions =
      additive_order_conditions(explicit_table, implicit_table, wE, wI, max_order, "b");
  int p = 0;
  for (int q = 1; q <= max_order; ++q) {
    if (first_violated_additive_condition(conditions, q, false, tol)) break;
    p = q;
  }
  return p;
}

}  // namespace stiffbench

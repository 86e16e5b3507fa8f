#include "core/tableau.hpp"

#include <Eigen/LU>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace stiffbench {

bool ButcherTableau::is_explicit() const {
  for (Index i = 0; i < a.rows(); ++i)
    for (Index j = i; j < a.cols(); ++j)
      if (a(i, j) != 0.0) return false;
  return true;
}

double ButcherTableau::row_sum_defect() const {
  return (c - a.rowwise().sum()).cwiseAbs().maxCoeff();
}

std::complex<double> ButcherTableau::stability(std::complex<double> z) const {
  const Index s = stages();
  const Eigen::MatrixXcd m = Eigen::MatrixXcd::Identity(s, s) - z * a.cast<std::complex<double>>();
  const Eigen::VectorXcd k = m.partialPivLu().solve(Eigen::VectorXcd::Ones(s));
  return 1.0 + z * b.cast<std::complex<double>>().dot(k);
}

namespace {

// A rooted tree as the multiset of its root's subtrees (indices into the tree list, sorted).
struct Tree {
  int order;
  std::vector<int> children;
  double gamma;  // density γ(τ) = |τ| Π γ(children)
};

// All rooted trees with at most max_order vertices, generated order by order: a tree of order n
// is a root plus a non-decreasing list of earlier trees whose orders sum to n - 1.
std::vector<Tree> build_rooted_trees(int max_order) {
  std::vector<Tree> trees;
  trees.push_back({1, {}, 1.0});
  for (int n = 2; n <= max_order; ++n) {
    const int count_before = static_cast<int>(trees.size());
    std::vector<int> pick;
    std::function<void(int, int)> rec = [&](int remaining, int min_index) {
      if (remaining == 0) {
        double g = n;
        for (int ch : pick) g *= trees[static_cast<std::size_t>(ch)].gamma;
        trees.push_back({n, pick, g});
        return;
      }
      for (int i = min_index; i < count_before; ++i) {
        const int o = trees[static_cast<std::size_t>(i)].order;
        if (o > remaining) continue;
        pick.push_back(i);
        rec(remaining - o, i);
        pick.pop_back();
      }
    };
    rec(n - 1, 0);
  }
  return trees;
}

const std::vector<Tree>& rooted_trees_to_6() {
  static const std::vector<Tree> trees = build_rooted_trees(6);
  return trees;
}

}  // namespace

double ButcherTableau::order_defect(const Vec& weights, int p) const {
  if (p < 1 || p > 6) throw std::logic_error("order_defect: order must be in 1..6");
  const auto& trees = rooted_trees_to_6();
  // Elementary weights Φ(τ)_i = Π_{children u} (A Φ(u))_i, with Φ(•) = 1.
  std::vector<Vec> phi;
  phi.reserve(trees.size());
  double worst = 0;
  for (const Tree& t : trees) {
    Vec v = Vec::Ones(stages());
    for (int ch : t.children) v = v.cwiseProduct(a * phi[static_cast<std::size_t>(ch)]);
    phi.push_back(v);
    if (t.order == p) worst = std::max(worst, std::abs(weights.dot(v) - 1.0 / t.gamma));
  }
  return worst;
}

int ButcherTableau::satisfied_order(double tol, int max_order) const {
  int p = 0;
  while (p < max_order && order_defect(p + 1) <= tol) ++p;
  return p;
}

int ButcherTableau::satisfied_order(const Vec& weights, double tol, int max_order) const {
  int p = 0;
  while (p < max_order && order_defect(weights, p + 1) <= tol) ++p;
  return p;
}

int ButcherTableau::satisfied_stage_order(double tol) const {
  const Index s = stages();
  int q = 0;
  // C(k): Σ_j a_ij c_j^(k-1) = c_i^k / k for every stage i.
  for (int k = 1; k <= s; ++k) {
    const Vec lhs = a * c.array().pow(k - 1).matrix();
    const Vec rhs = c.array().pow(k) / static_cast<double>(k);
    if ((lhs - rhs).cwiseAbs().maxCoeff() > tol) break;
    q = k;
  }
  return q;
}

bool ButcherTableau::coefficients_fsal() const {
  const Index s = stages();
  if (s < 1 || a.rows() != s || a.cols() != s) return false;
  return (a.row(s - 1).transpose() - b).cwiseAbs().maxCoeff() <= 1e-12;
}

namespace {

std::string num(double x) {
  std::ostringstream os;
  os.precision(3);
  os << x;
  return os.str();
}

}  // namespace

std::string ButcherTableau::defect(Shape shape) const {
  const Index s = stages();
  const auto n = [](Index k) { return std::to_string(k); };
  if (s < 1) return "b is empty (no stages)";
  if (a.rows() != s || a.cols() != s)
    return "A is " + n(a.rows()) + "x" + n(a.cols()) + ", b has " + n(s) + " entries (need A " +
           n(s) + "x" + n(s) + ")";
  if (c.size() != s) return "c has " + n(c.size()) + " entries, b has " + n(s);
  if (b_embedded.size() != 0 && b_embedded.size() != s)
    return "b_embedded has " + n(b_embedded.size()) + " entries, b has " + n(s);
  if (!a.allFinite() || !b.allFinite() || !c.allFinite() || !b_embedded.allFinite())
    return "a coefficient is not finite";
  for (Index i = 0; i < s; ++i) {
    const double sum = a.row(i).sum();
    if (std::abs(c[i] - sum) > 1e-12 * std::max(1.0, std::abs(sum)))
      return "c[" + n(i) + "] = " + num(c[i]) + " is not the row sum of A (" + num(sum) + ")";
  }
  if (shape != Shape::any)
    for (Index i = 0; i < s; ++i)
      for (Index j = shape == Shape::explicit_rk ? i : i + 1; j < s; ++j)
        if (a(i, j) != 0.0)
          return std::string(shape == Shape::explicit_rk ? "an explicit"
                                                         : "a diagonally implicit") +
                 " method needs A strictly lower triangular" +
                 (shape == Shape::explicit_rk ? "" : " up to the diagonal") + ": a(" + n(i) + "," +
                 n(j) + ") = " + num(a(i, j));
  if (order < 1) return "claims no order (order = " + std::to_string(order) + ")";
  for (int p = 1; p <= std::min(order, 6); ++p)
    if (const double d = order_defect(b, p); !(d <= 1e-12))
      return "claims order " + std::to_string(order) + " but an order-" + std::to_string(p) +
             " condition fails by " + num(d) +
             (p == 1 ? " (the weights b sum to " + num(b.sum()) + ")" : "");
  if (b_embedded.size() != 0) {
    if (embedded_order < 1) return "has embedded weights but claims no embedded order";
    for (int p = 1; p <= std::min(embedded_order, 6); ++p)
      if (const double d = order_defect(b_embedded, p); !(d <= 1e-12))
        return "claims embedded order " + std::to_string(embedded_order) + " but an order-" +
               std::to_string(p) + " condition of b_embedded fails by " + num(d) +
               (p == 1 ? " (the embedded weights sum to " + num(b_embedded.sum()) + ")" : "");
  } else if (embedded_order != 0) {
    return "claims embedded order " + std::to_string(embedded_order) + " without embedded weights";
  }
  if (stage_order > 0 && satisfied_stage_order() < stage_order)
    return "claims stage order " + std::to_string(stage_order) +
           " but C(q) holds only for q = " + std::to_string(satisfied_stage_order());
  if (fsal && !coefficients_fsal())
    return "claims first same as last (fsal) but the last row of A is not b";
  return {};
}

void ButcherTableau::validate(Shape shape) {
  const std::string who = "tableau '" + (name.empty() ? std::string("(unnamed)") : name) + "': ";
  if (c.size() == 0 && a.rows() == a.cols() && a.rows() == b.size() && b.size() > 0)
    c = a.rowwise().sum();
  const std::string d = defect(shape);
  if (!d.empty()) throw BadInput(who + d);
}

int KickDriftCoefficients::evaluations_per_step() const {
  int n = 0;
  for (double k : kick) n += k != 0.0;
  return n;
}

double KickDriftCoefficients::order_defect(int p) const {
  double sk = 0, sd = 0, second = 0, drift_before = 0;
  for (std::size_t j = 0; j < kick.size(); ++j) {
    sk += kick[j];
    second += kick[j] * drift_before;
    drift_before += drift[j];
    sd += drift[j];
  }
  if (p == 1) return std::max(std::abs(sk - 1.0), std::abs(sd - 1.0));
  if (p == 2) return std::abs(second - 0.5);
  throw std::logic_error("KickDriftCoefficients::order_defect: only orders 1 and 2 are checked");
}

}  // namespace stiffbench

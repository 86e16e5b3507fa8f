#include "core/tableau.hpp"

#include <Eigen/LU>
#include <cmath>
#include <functional>
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

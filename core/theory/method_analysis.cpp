#include "core/theory/method_analysis.hpp"

#include "core/run_control.hpp"
#include "core/theory/additive_conditions.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numbers>

namespace stiffbench {

namespace {

using ld = long double;
using cld = std::complex<long double>;
using MatL = Eigen::Matrix<ld, Eigen::Dynamic, Eigen::Dynamic>;
using VecL = Eigen::Matrix<ld, Eigen::Dynamic, 1>;

constexpr int kMaxOrder = 8;
constexpr double kConditionTol = 1e-12;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Unbounded stability intervals are sampled up to this length for the internal amplification.
constexpr double kInternalCap = 100.0;
// Terms of the series of log R(z) − z (dissipation and dispersion orders).
constexpr int kSeriesDegree = 20;

// Bracket name of a tree from its children (non-decreasing indices, so equal ones are adjacent).
template <class Tree>
std::string tree_name(const std::vector<Tree>& trees, const std::vector<int>& children) {
  if (children.empty()) return "t";
  std::string out = "[";
  for (std::size_t i = 0; i < children.size();) {
    std::size_t j = i;
    while (j < children.size() && children[j] == children[i]) ++j;
    if (i > 0) out += ",";
    out += trees[static_cast<std::size_t>(children[i])].name;
    if (j - i > 1) out += "^" + std::to_string(j - i);
    i = j;
  }
  return out + "]";
}

// The one enumerator of the rooted trees (RootedTree) and the bi-coloured trees of W-methods
// (WTree): visit(children) for every non-decreasing list of indices into trees[0, before) whose
// orders sum to `sum` (each multiset of earlier trees once), in lexicographic order. These are
// the subtrees of the trees of order sum + 1 with an ordinary root; visit may append to trees.
template <class Tree, class Visit>
void for_each_subtree_multiset(const std::vector<Tree>& trees, int before, int sum, Visit visit) {
  std::vector<int> pick;
  std::function<void(int, int)> rec = [&](int remaining, int min_index) {
    if (remaining == 0) {
      visit(pick);
      return;
    }
    for (int i = min_index; i < before; ++i) {
      const int o = trees[static_cast<std::size_t>(i)].order;
      if (o > remaining) continue;
      pick.push_back(i);
      rec(remaining - o, i);
      pick.pop_back();
    }
  };
  rec(sum, 0);
}

// The tree of order n with an ordinary root over `children`: γ(t) = n Π γ(u) and
// σ(t) = Π_u σ(u)^m m! over the distinct subtrees u of multiplicity m, and its bracket name.
template <class Tree>
Tree tree_over(const std::vector<Tree>& trees, int n, const std::vector<int>& children) {
  Tree t;
  t.order = n;
  t.children = children;
  t.density = n;
  t.symmetry = 1.0;
  for (std::size_t i = 0; i < children.size();) {
    std::size_t j = i;
    while (j < children.size() && children[j] == children[i]) ++j;
    const Tree& u = trees[static_cast<std::size_t>(children[i])];
    for (std::size_t k = i; k < j; ++k) {
      t.density *= u.density;
      t.symmetry *= u.symmetry * static_cast<double>(k - i + 1);
    }
    i = j;
  }
  t.name = tree_name(trees, children);
  return t;
}

// All rooted trees with at most kMaxOrder vertices, order by order: a tree of order n is a root
// plus a non-decreasing list of earlier trees whose orders sum to n − 1 (each multiset once).
std::vector<RootedTree> build_rooted_trees() {
  std::vector<RootedTree> trees;
  trees.push_back({1, {}, 1.0, 1.0, "t"});
  for (int n = 2; n <= kMaxOrder; ++n)
    for_each_subtree_multiset(
        trees, static_cast<int>(trees.size()), n - 1,
        [&](const std::vector<int>& children) { trees.push_back(tree_over(trees, n, children)); });
  return trees;
}

// The conditions of the trees of order <= max_order for weights w, with elementary weights
// Φ(t) = Π_children (M Φ(u)) where M = `single` for a vertex with one son and `multi` otherwise
// (Runge–Kutta: both A; Rosenbrock: β = α + Γ and α), in long double.
std::vector<OrderCondition> conditions_from(const MatL& multi, const MatL& single, const VecL& w,
                                            int max_order) {
  require_input(max_order >= 1 && max_order <= kMaxOrder,
                "order conditions: the largest order must be in 1..8");
  const auto& trees = rooted_trees();
  const Index s = w.size();
  std::vector<VecL> phi;
  phi.reserve(trees.size());
  std::vector<OrderCondition> out;
  for (std::size_t i = 0; i < trees.size(); ++i) {
    const RootedTree& t = trees[i];
    if (t.order > max_order) break;
    poll_run_control();  // a large tableau stops at an interrupt or --max-wall
    VecL v = VecL::Ones(s);
    if (t.children.size() == 1)
      v = single * phi[static_cast<std::size_t>(t.children[0])];
    else
      for (int ch : t.children) v = v.cwiseProduct(multi * phi[static_cast<std::size_t>(ch)]);
    const ld residual = w.dot(v) - 1.0L / static_cast<ld>(t.density);
    phi.push_back(std::move(v));
    out.push_back({t.order, static_cast<int>(i), t.name, static_cast<double>(residual),
                   static_cast<double>(residual / static_cast<ld>(t.symmetry))});
  }
  return out;
}

// Largest p <= 8 with every condition of order <= p met to kConditionTol.
int achieved_order(const std::vector<OrderCondition>& c) {
  const auto first = first_violated_condition(c, kMaxOrder, kConditionTol);
  return first ? first->order - 1 : kMaxOrder;
}

// Order, residual per order and principal error norms from m.conditions.
void fill_order(MethodAnalysis& m) {
  m.order = achieved_order(m.conditions);
  m.residual_by_order.assign(kMaxOrder, 0.0);
  for (const OrderCondition& c : m.conditions)
    m.residual_by_order[static_cast<std::size_t>(c.order - 1)] =
        std::max(m.residual_by_order[static_cast<std::size_t>(c.order - 1)], std::abs(c.residual));
  auto norms = [&](int order, double& two, double& max) {
    ld sum = 0;
    for (const OrderCondition& c : m.conditions)
      if (c.order == order) {
        sum += static_cast<ld>(c.error_coefficient) * c.error_coefficient;
        max = std::max(max, std::abs(c.error_coefficient));
      }
    two = static_cast<double>(std::sqrt(sum));
  };
  if (m.order + 1 <= kMaxOrder) {
    norms(m.order + 1, m.error_norm_2, m.error_norm_max);
  } else {
    m.notes.push_back("order 8 or more: no error coefficients (trees to order 8 only)");
  }
  if (m.order + 2 <= kMaxOrder)
    norms(m.order + 2, m.error_norm_2_next, m.error_norm_max_next);
  else if (m.order + 1 <= kMaxOrder)
    m.notes.push_back("error norms of order p+2 = " + std::to_string(m.order + 2) +
                      " not computed (trees to order 8 only)");
}

cld horner(const Polynomial& c, cld z) {
  cld v = 0;
  for (std::size_t k = c.size(); k-- > 0;) v = v * z + static_cast<ld>(c[k]);
  return v;
}

// Σ_j |Q_j(z)|, Q_j(z) = z bᵀ(I − zA)⁻¹ e_j, largest over z = unit·r, r ∈ [0, r_max] (n samples).
double internal_amplification(const Mat& a, const Vec& b, std::complex<double> unit, double r_max,
                              int n = 2001) {
  using cd = std::complex<double>;
  const Index s = b.size();
  double worst = 0;
  for (int k = 0; k < n; ++k) {
    const cd z = unit * (r_max * k / (n - 1));
    const Eigen::MatrixXcd m = Eigen::MatrixXcd::Identity(s, s) - z * a.cast<cd>();
    const Eigen::VectorXcd x = m.transpose().partialPivLu().solve(b.cast<cd>());
    double sum = 0;
    for (Index j = 0; j < s; ++j) sum += std::abs(z * x(j));
    if (std::isfinite(sum)) worst = std::max(worst, sum);
  }
  return worst;
}

// The coefficients l_k (k = 0..n) of log R(z) − z, with bounds on the magnitude of the terms
// that formed each (for telling round-off from a true coefficient).
void log_series(const RationalForm& r, int n, std::vector<ld>& l, std::vector<ld>& bound) {
  auto at = [](const Polynomial& c, int k) {
    return k < static_cast<int>(c.size()) ? static_cast<ld>(c[static_cast<std::size_t>(k)]) : 0.0L;
  };
  const ld q0 = at(r.q, 0);
  std::vector<ld> rs(static_cast<std::size_t>(n + 1)), rb(rs.size());
  for (int k = 0; k <= n; ++k) {  // R = P/Q: Q·R = P
    ld v = at(r.p, k), vb = std::abs(at(r.p, k));
    for (int j = 1; j <= k; ++j) {
      v -= at(r.q, j) * rs[static_cast<std::size_t>(k - j)];
      vb += std::abs(at(r.q, j)) * rb[static_cast<std::size_t>(k - j)];
    }
    rs[static_cast<std::size_t>(k)] = v / q0;
    rb[static_cast<std::size_t>(k)] = vb / std::abs(q0);
  }
  // S = log R: R S' = R', so k s_k r_0 = k r_k − Σ_{j=1}^{k−1} j s_j r_{k−j}.
  l.assign(rs.size(), 0.0L);
  bound.assign(rs.size(), 0.0L);
  for (int k = 1; k <= n; ++k) {
    ld v = static_cast<ld>(k) * rs[static_cast<std::size_t>(k)];
    ld vb = static_cast<ld>(k) * rb[static_cast<std::size_t>(k)];
    for (int j = 1; j < k; ++j) {
      v -=
          static_cast<ld>(j) * l[static_cast<std::size_t>(j)] * rs[static_cast<std::size_t>(k - j)];
      vb += static_cast<ld>(j) * bound[static_cast<std::size_t>(j)] *
            rb[static_cast<std::size_t>(k - j)];
    }
    l[static_cast<std::size_t>(k)] = v / (static_cast<ld>(k) * rs[0]);
    bound[static_cast<std::size_t>(k)] = vb / (static_cast<ld>(k) * std::abs(rs[0]));
  }
  if (n >= 1) {
    l[1] -= 1.0L;  // − z
    bound[1] += 1.0L;
  }
}

// Everything that follows from R = P/Q (and the stage matrix, for internal stability).
void fill_stability(MethodAnalysis& m, const LinearStability& s, const Mat& a, const Vec& b) {
  m.p = s.rational->p;
  m.q = s.rational->q;
  const std::size_t dp = m.p.size() - 1, dq = m.q.size() - 1;
  m.r_infinity = dp > dq ? kInf : dp < dq ? 0.0 : std::abs(m.p.back() / m.q.back());
  m.a_stable = a_stable_exact(s).value_or(false);
  m.l_stable = m.a_stable && m.r_infinity <= 1e-12;
  const AxisLimit re = real_axis_limit(s), im = imaginary_axis_limit(s);
  m.real_axis_limit = re.limit;
  m.real_axis_unbounded = re.unbounded;
  m.imag_axis_limit = im.limit;
  m.imag_axis_unbounded = im.unbounded;
  const double r_re = re.unbounded ? kInternalCap : re.limit;
  const double r_im = im.unbounded ? kInternalCap : im.limit;
  m.internal_amplification_real = internal_amplification(a, b, {-1.0, 0.0}, r_re);
  // |Q_j(z̄)| = |Q_j(z)|: the half [0, i·r] covers [−i·r, i·r].
  m.internal_amplification_imag = internal_amplification(a, b, {0.0, 1.0}, r_im);
  if (re.unbounded || im.unbounded)
    m.notes.push_back("internal amplification on an unbounded axis interval sampled up to |z| = " +
                      std::to_string(static_cast<int>(kInternalCap)));
  std::vector<ld> l, bound;
  log_series(*s.rational, kSeriesDegree, l, bound);
  for (int k = 2; k <= kSeriesDegree; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    if (std::abs(l[uk]) <= 1e-12L * bound[uk]) continue;
    int& order = k % 2 == 0 ? m.dissipation_order : m.dispersion_order;
    if (order == 0) order = k;
  }
  if (m.dissipation_order == 0)
    m.notes.push_back("no dissipation: |R(iy)| = 1 to degree " + std::to_string(kSeriesDegree) +
                      " of the series of log R(z) - z");
  if (m.dispersion_order == 0)
    m.notes.push_back("no dispersion: arg R(iy) = y to degree " + std::to_string(kSeriesDegree) +
                      " of the series of log R(z) - z");
}

double max_abs(const Mat& a) { return a.size() ? a.cwiseAbs().maxCoeff() : 0.0; }
double max_abs(const Vec& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

// K(I + rK)⁻¹ >= 0 and rK(I + rK)⁻¹1 <= 1 elementwise (Kraaijevanger's absolute monotonicity
// of K at r), in long double; a violation must exceed 1e-13·r (round-off of the coefficients).
bool absolutely_monotonic(const MatL& k, ld r) {
  const Index n = k.rows();
  const MatL m = MatL::Identity(n, n) + r * k;
  const Eigen::FullPivLU<MatL> lu(m);
  if (!lu.isInvertible()) return false;
  const MatL p = k * lu.inverse();
  const ld tol = 1e-13L * std::max(r, 1e-5L);
  if (p.minCoeff() < -tol) return false;
  const VecL sums = r * p * VecL::Ones(n);
  return sums.maxCoeff() <= 1.0L + 1e-13L;
}

// The bi-coloured trees of W-methods up to kMaxWOrder vertices: a tree of order n is a W-vertex
// over one tree of order n − 1, or an f-vertex over a non-decreasing list of earlier trees whose
// orders sum to n − 1. σ(W[u]) = σ(u); σ of an f-root as for rooted trees. γ(t) is the density
// of the tree with the colours forgotten (a W-vertex counted as a vertex).
std::vector<WTree> build_w_trees() {
  std::vector<WTree> trees;
  trees.push_back({1, false, {}, false, 1.0, 1.0, "t"});
  for (int n = 2; n <= kMaxWOrder; ++n) {
    const int before = static_cast<int>(trees.size());
    for (int i = 0; i < before; ++i) {
      const WTree& u = trees[static_cast<std::size_t>(i)];
      if (u.order != n - 1) continue;
      trees.push_back({n, true, {i}, true, n * u.density, u.symmetry, "W[" + u.name + "]"});
    }
    for_each_subtree_multiset(trees, before, n - 1, [&](const std::vector<int>& children) {
      WTree t = tree_over(trees, n, children);
      for (int c : children) t.has_w = t.has_w || trees[static_cast<std::size_t>(c)].has_w;
      trees.push_back(std::move(t));
    });
  }
  return trees;
}

// The stability figures of the embedded formula R̂ = P̂/Q̂.
EmbeddedStability embedded_figures(const LinearStability& s) {
  EmbeddedStability e;
  e.p = s.rational->p;
  e.q = s.rational->q;
  const std::size_t dp = e.p.size() - 1, dq = e.q.size() - 1;
  e.r_infinity = dp > dq ? kInf : dp < dq ? 0.0 : std::abs(e.p.back() / e.q.back());
  e.a_stable = a_stable_exact(s).value_or(false);
  e.l_stable = e.a_stable && e.r_infinity <= 1e-12;
  const AxisLimit re = real_axis_limit(s), im = imaginary_axis_limit(s);
  e.real_axis_limit = re.limit;
  e.real_axis_unbounded = re.unbounded;
  e.imag_axis_limit = im.limit;
  e.imag_axis_unbounded = im.unbounded;
  return e;
}

}  // namespace

const std::vector<RootedTree>& rooted_trees() {
  static const std::vector<RootedTree> trees = build_rooted_trees();
  return trees;
}

const std::vector<WTree>& w_trees() {
  static const std::vector<WTree> trees = build_w_trees();
  return trees;
}

std::vector<OrderCondition> rosenbrock_w_conditions(const RosenbrockTableau& t, const Vec& w,
                                                    int max_order) {
  require_input(max_order >= 1 && max_order <= kMaxWOrder,
                "W-conditions: the largest order must be in 1..6");
  const Index s = w.size();
  require_input(s >= 1 && t.alpha.rows() == s && t.alpha.cols() == s && t.gamma_lower.rows() == s &&
                    t.gamma_lower.cols() == s,
                "W-conditions: alpha and gamma must be s x s with s the number of weights");
  const MatL alpha = t.alpha.cast<ld>();
  const MatL gamma = t.gamma_lower.cast<ld>() + static_cast<ld>(t.gamma) * MatL::Identity(s, s);
  const VecL wl = w.cast<ld>();
  const auto& trees = w_trees();
  std::vector<VecL> phi;
  std::vector<OrderCondition> out;
  for (std::size_t i = 0; i < trees.size(); ++i) {
    const WTree& tree = trees[i];
    if (tree.order > max_order) break;
    poll_run_control();
    VecL v = VecL::Ones(s);
    if (tree.w_root)
      v = gamma * phi[static_cast<std::size_t>(tree.children[0])];
    else
      for (int ch : tree.children) v = v.cwiseProduct(alpha * phi[static_cast<std::size_t>(ch)]);
    const ld residual = wl.dot(v) - (tree.has_w ? 0.0L : 1.0L / static_cast<ld>(tree.density));
    phi.push_back(std::move(v));
    out.push_back({tree.order, static_cast<int>(i), tree.name, static_cast<double>(residual),
                   static_cast<double>(residual / static_cast<ld>(tree.symmetry))});
  }
  return out;
}

int rosenbrock_w_order(const RosenbrockTableau& t, const Vec& w, double tol) {
  const auto first =
      first_violated_condition(rosenbrock_w_conditions(t, w, kMaxWOrder), kMaxWOrder, tol);
  return first ? first->order - 1 : kMaxWOrder;
}

std::vector<OrderCondition> rk_order_conditions(const ButcherTableau& t, const Vec& w,
                                                int max_order) {
  const Index s = w.size();
  require_input(t.a.rows() == s && t.a.cols() == s,
                "order conditions: A must be s x s with s the number of weights");
  const MatL a = t.a.cast<ld>();
  return conditions_from(a, a, w.cast<ld>(), max_order);
}

std::optional<OrderCondition> first_violated_condition(const std::vector<OrderCondition>& c,
                                                       int order, double tol) {
  std::optional<OrderCondition> first;
  for (const OrderCondition& x : c)
    if (x.order <= order && !(std::abs(x.residual) <= tol) && (!first || x.order < first->order))
      first = x;
  return first;
}

// Whether P/Q and P̂/Q̂ are one rational function: P·Q̂ = P̂·Q coefficient by coefficient, to
// 1e-12 of the largest product coefficient.
bool same_rational(const RationalForm& r, const RationalForm& e) {
  if (r.p.empty() || r.q.empty() || e.p.empty() || e.q.empty()) return false;
  Polynomial x = poly_multiply(r.p, e.q), y = poly_multiply(e.p, r.q);
  x.resize(std::max(x.size(), y.size()), 0.0);
  y.resize(x.size(), 0.0);
  double scale = 0, diff = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    scale = std::max({scale, std::abs(x[k]), std::abs(y[k])});
    diff = std::max(diff, std::abs(x[k] - y[k]));
  }
  return diff <= 1e-12 * scale;
}

// The note of an embedded pair whose embedded weights have the method's own R(z) (ros3p): on
// y' = Jy with constant J both solutions are R(hJ)y, so the estimate is round-off.
void note_embedded_stability(MethodAnalysis& m, const LinearStability& main,
                             const LinearStability& embedded) {
  if (!main.rational || !embedded.rational || !same_rational(*main.rational, *embedded.rational))
    return;
  m.embedded_same_stability = true;
  m.notes.push_back(
      "the embedded weights have the same stability function R(z): on linear problems with a "
      "constant Jacobian the error estimate is round-off, so an adaptive run's step there is "
      "limited only by h_max and the output times (work-precision names such runs)");
}

MethodAnalysis analyze_runge_kutta(const ButcherTableau& t, const std::string& kind) {
  ButcherTableau tab = t;
  const Index s = tab.stages();
  require_input(s >= 1 && tab.a.rows() == s && tab.a.cols() == s,
                "analyze: tableau '" + t.name + "' needs A s x s and b with s >= 1 entries");
  if (tab.c.size() == 0) tab.c = tab.a.rowwise().sum();
  MethodAnalysis m;
  m.name = t.name;
  m.kind = kind;
  m.stages = static_cast<int>(s);
  m.claimed_order = t.order;
  m.conditions = rk_order_conditions(tab, tab.b, kMaxOrder);
  fill_order(m);
  m.stage_order = tab.satisfied_stage_order();
  if (tab.b_embedded.size() == s)
    m.embedded_order = achieved_order(rk_order_conditions(tab, tab.b_embedded, kMaxOrder));
  // Stiffly accurate: a_sj = b_j (Hairer & Wanner II, IV.6); first same as last: in addition an
  // explicit first stage (a_1j = 0), so the last stage's f is the next step's first.
  m.stiffly_accurate = tab.coefficients_fsal();
  m.fsal = m.stiffly_accurate && tab.a.row(0).cwiseAbs().maxCoeff() == 0.0;
  m.max_coefficient = std::max({max_abs(tab.a), max_abs(tab.b), max_abs(tab.c)});
  const LinearStability stab = tableau_stability(tab);
  fill_stability(m, stab, tab.a, tab.b);
  if (tab.b_embedded.size() == s) {
    ButcherTableau embedded = tab;
    embedded.b = tab.b_embedded;
    const LinearStability es = tableau_stability(embedded);
    note_embedded_stability(m, stab, es);
    if (es.rational) m.embedded_stability = embedded_figures(es);
  }
  if (tab.is_explicit()) {
    m.ssp_coefficient = ssp_coefficient(tab);
    m.notes.push_back(
        "SSP coefficient: radius of absolute monotonicity (exact test in long "
        "double, bisection to 1e-12 relative)");
  }
  return m;
}

MethodAnalysis analyze_rosenbrock(const RosenbrockTableau& t) {
  const Index s = t.stages();
  require_input(s >= 1 && t.alpha.rows() == s && t.alpha.cols() == s && t.gamma_lower.rows() == s &&
                    t.gamma_lower.cols() == s,
                "analyze: Rosenbrock tableau '" + t.name + "' needs alpha, gamma s x s");
  const Mat gamma = t.gamma_lower + t.gamma * Mat::Identity(s, s);
  const Mat beta = t.alpha + gamma;
  MethodAnalysis m;
  m.name = t.name;
  m.kind = "rosenbrock";
  m.stages = static_cast<int>(s);
  m.claimed_order = t.order;
  const MatL al = t.alpha.cast<ld>(), bl = beta.cast<ld>();
  m.conditions = conditions_from(al, bl, t.b.cast<ld>(), kMaxOrder);
  fill_order(m);
  if (t.b_embedded.size() == s)
    m.embedded_order = achieved_order(conditions_from(al, bl, t.b_embedded.cast<ld>(), kMaxOrder));
  m.w_conditions = rosenbrock_w_conditions(t, t.b, kMaxWOrder);
  const auto w_fail = first_violated_condition(m.w_conditions, kMaxWOrder, kConditionTol);
  m.w_order = w_fail ? w_fail->order - 1 : kMaxWOrder;
  m.embedded_w_order = t.b_embedded.size() == s ? rosenbrock_w_order(t, t.b_embedded) : 0;
  m.claimed_w_order = t.w_order;
  // Stiffly accurate (HW II, IV.7): b_i = β_si and α_s = 1, so y⁺ is the last stage's argument
  // plus k_s (R(∞) = 0 when in addition the method is A-stable).
  m.stiffly_accurate = (beta.row(s - 1).transpose() - t.b).cwiseAbs().maxCoeff() <= 1e-12 &&
                       std::abs(t.alpha.row(s - 1).sum() - 1.0) <= 1e-12;
  m.max_coefficient = std::max({max_abs(t.alpha), max_abs(gamma), max_abs(t.b)});
  m.notes.push_back(
      "Rosenbrock: order conditions of Hairer & Wanner II, IV.7 (exact Jacobian); W-order from "
      "the conditions with an arbitrary matrix W in place of J (bi-coloured trees to order 6, "
      "autonomous problems); stability from A = alpha + Gamma");
  const LinearStability stab = rosenbrock_stability(t.alpha, gamma, t.b);
  fill_stability(m, stab, beta, t.b);
  if (t.b_embedded.size() == s) {
    const LinearStability es = rosenbrock_stability(t.alpha, gamma, t.b_embedded);
    note_embedded_stability(m, stab, es);
    if (es.rational) m.embedded_stability = embedded_figures(es);
  }
  return m;
}

std::vector<DispersionPoint> dissipation_dispersion(const RationalForm& r, int n) {
  require_input(n >= 2, "dissipation_dispersion: need at least 2 points");
  std::vector<DispersionPoint> out;
  const int sub = 32;  // unwrapping steps between two output points
  auto value = [&](ld nu) { return horner(r.p, cld(0, nu)) / horner(r.q, cld(0, nu)); };
  ld nu_prev = 0.0L, phase = 0.0L;
  cld r_prev = 1.0L;
  for (int k = 0; k < n; ++k) {
    const ld nu = std::pow(10.0L, -2.0L + 3.0L * k / (n - 1));
    cld rv = r_prev;
    for (int j = 1; j <= sub; ++j) {
      const ld x = nu_prev + (nu - nu_prev) * j / sub;
      rv = value(x);
      if (std::abs(rv) > 0 && std::abs(r_prev) > 0) phase += std::arg(rv / r_prev);
      r_prev = rv;
    }
    nu_prev = nu;
    out.push_back({static_cast<double>(nu), static_cast<double>(std::abs(rv)),
                   static_cast<double>(phase - nu)});
  }
  return out;
}

double ssp_coefficient(const ButcherTableau& t) {
  const Index s = t.stages();
  require_input(t.a.rows() == s && t.a.cols() == s, "ssp_coefficient: A must be s x s");
  MatL k = MatL::Zero(s + 1, s + 1);
  k.topLeftCorner(s, s) = t.a.cast<ld>();
  k.block(s, 0, 1, s) = t.b.cast<ld>().transpose();
  if (!absolutely_monotonic(k, 0.0L)) return 0.0;
  // Absolute monotonicity at r implies it on [0, r] (Kraaijevanger 1991, Lemma 4.4), so the
  // feasible set is an interval: bracket its end by doubling, then bisect to 1e-12 relative.
  ld lo = 0.0L, hi = 1.0L;
  while (absolutely_monotonic(k, hi)) {
    lo = hi;
    hi *= 2.0L;
    if (hi > 1e6L) return kInf;
  }
  while (hi - lo > 1e-13L * hi && hi > 1e-12L) {
    const ld mid = 0.5L * (lo + hi);
    (absolutely_monotonic(k, mid) ? lo : hi) = mid;
  }
  if (hi <= 1e-12L) return 0.0;
  // The bracket is 1e-13 relative and the feasibility test admits violations of 1e-13·r, so the
  // digits beyond the twelfth are bisection noise (ssprk3 would read 1.0000000000000568):
  // reported to 12 significant digits.
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12g", static_cast<double>(lo));
  return std::strtod(buf, nullptr);
}

// ---- Kick/drift splittings: the free Lie algebra ------------------------------------------------

namespace {

// The truncated tensor algebra over the letters A (drift, 0) and B (kick, 1), words of degree
// <= 8: the coefficient of a word of degree d with letters as binary digits w is at 2^d − 1 + w.
struct Tensor {
  std::vector<ld> c = std::vector<ld>((std::size_t{2} << kMaxOrder) - 1, 0.0L);
  static std::size_t at(int degree, std::size_t word) {
    return (std::size_t{1} << degree) - 1 + word;
  }
};

Tensor operator*(const Tensor& x, const Tensor& y) {
  Tensor out;
  for (int i = 0; i <= kMaxOrder; ++i)
    for (int j = 0; i + j <= kMaxOrder; ++j)
      for (std::size_t u = 0; u < (std::size_t{1} << i); ++u) {
        const ld xu = x.c[Tensor::at(i, u)];
        if (xu == 0.0L) continue;
        for (std::size_t v = 0; v < (std::size_t{1} << j); ++v)
          out.c[Tensor::at(i + j, (u << j) | v)] += xu * y.c[Tensor::at(j, v)];
      }
  return out;
}

Tensor letter_exp(int letter, ld coefficient) {  // exp(coefficient · letter)
  Tensor t;
  ld term = 1.0L;
  for (int d = 0; d <= kMaxOrder; ++d) {
    t.c[Tensor::at(d, letter ? (std::size_t{1} << d) - 1 : 0)] = term;
    term *= coefficient / static_cast<ld>(d + 1);
  }
  return t;
}

Tensor letter(int l) {
  Tensor t;
  t.c[Tensor::at(1, static_cast<std::size_t>(l))] = 1.0L;
  return t;
}

Tensor bracket(const Tensor& x, const Tensor& y) {
  Tensor xy = x * y, yx = y * x;
  for (std::size_t i = 0; i < xy.c.size(); ++i) xy.c[i] -= yx.c[i];
  return xy;
}

std::vector<ld> degree_part(const Tensor& t, int d) {
  return {t.c.begin() + static_cast<std::ptrdiff_t>(Tensor::at(d, 0)),
          t.c.begin() + static_cast<std::ptrdiff_t>(Tensor::at(d + 1, 0))};
}

// The part of v orthogonal to span(basis) (modified Gram–Schmidt, twice), in long double.
std::vector<ld> orthogonal_part(std::vector<ld> v, std::vector<std::vector<ld>> basis) {
  std::vector<std::vector<ld>> q;
  auto dot = [](const std::vector<ld>& a, const std::vector<ld>& b) {
    ld s = 0;
    for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
    return s;
  };
  auto remove = [&](std::vector<ld>& x) {
    for (int pass = 0; pass < 2; ++pass)
      for (const auto& e : q) {
        const ld d = dot(x, e);
        for (std::size_t i = 0; i < x.size(); ++i) x[i] -= d * e[i];
      }
  };
  for (auto& b : basis) {
    const ld norm0 = std::sqrt(dot(b, b));
    remove(b);
    const ld norm = std::sqrt(dot(b, b));
    if (norm <= 1e-12L * norm0 || norm == 0.0L) continue;
    for (ld& x : b) x /= norm;
    q.push_back(b);
  }
  remove(v);
  return v;
}

}  // namespace

MethodAnalysis analyze_kick_drift(const KickDriftCoefficients& c) {
  require_input(!c.kick.empty() && c.kick.size() == c.drift.size(),
                "analyze: splitting '" + c.name + "' needs kick and drift of one length >= 1");
  MethodAnalysis m;
  m.name = c.name;
  m.kind = "splitting";
  m.stages = static_cast<int>(c.kick.size());
  m.claimed_order = c.order;
  m.stage_order = -1;
  // One step as a product of exponentials: kick_j (B), then drift_j (A), j = 1..s. (The order
  // in which the flows compose reverses the words; it changes no order and no residual.)
  Tensor step = letter_exp(0, 0.0L);
  for (std::size_t j = 0; j < c.kick.size(); ++j)
    step = step * letter_exp(1, c.kick[j]) * letter_exp(0, c.drift[j]);
  Tensor x = step;
  x.c[0] = 0.0L;  // step − 1
  Tensor log, power = letter_exp(0, 0.0L);
  for (int k = 1; k <= kMaxOrder; ++k) {
    power = power * x;
    for (std::size_t i = 0; i < log.c.size(); ++i)
      log.c[i] += (k % 2 ? 1.0L : -1.0L) * power.c[i] / static_cast<ld>(k);
  }
  log.c[Tensor::at(1, 0)] -= 1.0L;  // − (A + B)
  log.c[Tensor::at(1, 1)] -= 1.0L;
  // For x'' = a(x) the kick field B = a(x)∂_v and the drift A = v∂_x satisfy [B,[B,[B,A]]] = 0
  // (the Runge–Kutta–Nyström case; Blanes & Moan 2002): terms in the Lie ideal it generates
  // (spanned by the iterated brackets ad_x1 … ad_xm [B,[B,[B,A]]]) do not count.
  const Tensor a = letter(0), b = letter(1);
  std::vector<Tensor> ideal = {bracket(b, bracket(b, bracket(b, a)))};
  int free_order = 0;
  bool free_ok = true;
  for (int d = 1; d <= kMaxOrder; ++d) {
    const std::vector<ld> part = degree_part(log, d);
    ld free_res = 0;
    for (ld v : part) free_res = std::max(free_res, std::abs(v));
    std::vector<ld> reduced = part;
    if (d >= 4) {
      std::vector<std::vector<ld>> basis;
      for (const Tensor& e : ideal) basis.push_back(degree_part(e, d));
      reduced = orthogonal_part(part, basis);
      std::vector<Tensor> next;
      for (const Tensor& e : ideal) {
        next.push_back(bracket(a, e));
        next.push_back(bracket(b, e));
      }
      ideal = std::move(next);
    }
    ld res = 0, sum = 0;
    for (ld v : reduced) {
      res = std::max(res, std::abs(v));
      sum += v * v;
    }
    free_ok = free_ok && free_res <= kConditionTol;
    if (free_ok) free_order = d;
    m.conditions.push_back({d, -1, "Lie terms of degree " + std::to_string(d),
                            static_cast<double>(res), static_cast<double>(std::sqrt(sum))});
  }
  m.order = achieved_order(m.conditions);
  m.residual_by_order.assign(kMaxOrder, 0.0);
  for (const OrderCondition& k : m.conditions)
    m.residual_by_order[static_cast<std::size_t>(k.order - 1)] = k.residual;
  // Error norms: the 2-norm (error_coefficient above) and the largest coefficient of the
  // remaining words of degree p+1 and p+2.
  auto set = [&](int d, double& two, double& max) {
    if (d > kMaxOrder) return;
    two = m.conditions[static_cast<std::size_t>(d - 1)].error_coefficient;
    max = m.conditions[static_cast<std::size_t>(d - 1)].residual;
  };
  set(m.order + 1, m.error_norm_2, m.error_norm_max);
  set(m.order + 2, m.error_norm_2_next, m.error_norm_max_next);
  if (free_order != m.order)
    m.notes.push_back("order " + std::to_string(m.order) +
                      " for x'' = a(x) (modulo [B,[B,[B,A]]]); in the free Lie algebra " +
                      std::to_string(free_order));
  m.notes.push_back(
      "splitting: order conditions in the free Lie algebra of kick (B) and drift "
      "(A), modulo [B,[B,[B,A]]] = 0 (x'' = a(x)); no stability function");
  for (std::size_t j = 0; j < c.kick.size(); ++j)
    m.max_coefficient = std::max({m.max_coefficient, std::abs(c.kick[j]), std::abs(c.drift[j])});
  const AxisLimit osc = oscillator_limit(kick_drift_stability(c));
  m.oscillator_limit = osc.limit;
  if (osc.unbounded) m.notes.push_back("stable on the undamped oscillator for every step");
  return m;
}

MethodAnalysis analyze_additive(const AdditiveTableau& t) {
  const ButcherTableau& e = t.explicit_table;
  const ButcherTableau& i = t.implicit_table;
  const Index s = t.stages();
  require_input(s >= 1 && e.a.rows() == s && e.a.cols() == s && i.a.rows() == s &&
                    i.a.cols() == s && e.b.size() == s && i.b.size() == s,
                "analyze: additive tableau '" + t.name +
                    "' needs two s x s tables and two b with s >= 1 entries");
  MethodAnalysis m;
  m.name = t.name;
  m.kind = "imex_ark";
  m.stages = static_cast<int>(s);
  m.claimed_order = t.order;
  for (const AdditiveCondition& c :
       additive_order_conditions(e, i, e.b, i.b, kMaxAdditiveOrder, "b"))
    m.conditions.push_back(
        {c.order, -1, c.name, c.residual, std::numeric_limits<double>::quiet_NaN()});
  m.order = additive_satisfied_order(e, i, e.b, i.b, kMaxAdditiveOrder, kConditionTol);
  if (t.has_embedded() && e.b_embedded.size() == s && i.b_embedded.size() == s)
    m.embedded_order = additive_satisfied_order(e, i, e.b_embedded, i.b_embedded, kMaxAdditiveOrder,
                                                kConditionTol);
  m.residual_by_order.assign(kMaxAdditiveOrder, 0.0);
  for (const OrderCondition& c : m.conditions)
    m.residual_by_order[static_cast<std::size_t>(c.order - 1)] =
        std::max(m.residual_by_order[static_cast<std::size_t>(c.order - 1)], std::abs(c.residual));
  m.stiffly_accurate = i.coefficients_fsal();
  m.max_coefficient = std::max({max_abs(e.a), max_abs(e.b), max_abs(i.a), max_abs(i.b)});
  if (e.c.size() == s) m.max_coefficient = std::max(m.max_coefficient, max_abs(e.c));
  if (i.c.size() == s) m.max_coefficient = std::max(m.max_coefficient, max_abs(i.c));
  m.notes.push_back(
      "additive order conditions (bi-coloured trees; Hairer, Nørsett & Wanner I, "
      "II.15; Kennedy & Carpenter 2003) to order " +
      std::to_string(kMaxAdditiveOrder) +
      ", the coupling ones included; no error coefficients; the pair has no "
      "stability function of its own (each table alone: " +
      t.name + ":explicit, " + t.name + ":implicit)");
  return m;
}

}  // namespace stiffbench

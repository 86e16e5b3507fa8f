#include "core/theory/tableau.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/theory/method_analysis.hpp"

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

double ButcherTableau::order_defect(const Vec& weights, int p) const {
  if (p < 1 || p > 8) throw std::logic_error("order_defect: order must be in 1..8");
  double worst = 0;
  for (const OrderCondition& x : rk_order_conditions(*this, weights, p))
    if (x.order == p) worst = std::max(worst, std::abs(x.residual));
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
  // The first violated order condition (Butcher's trees up to order 8): its tree and residual.
  auto violated = [&](const Vec& w, int claim) {
    return first_violated_condition(rk_order_conditions(*this, w, std::min(claim, 8)), claim);
  };
  auto condition = [](const OrderCondition& v) {
    return "the condition of tree " + v.name + " (order " + std::to_string(v.order) +
           ") has residual " + num(v.residual);
  };
  if (const auto v = violated(b, order))
    return "order " + std::to_string(order) + " claimed but " + condition(*v) +
           (v->order == 1 ? " (the weights b sum to " + num(b.sum()) + ")" : "");
  if (b_embedded.size() != 0) {
    if (embedded_order < 1) return "has embedded weights but claims no embedded order";
    if (const auto v = violated(b_embedded, embedded_order))
      return "embedded order " + std::to_string(embedded_order) + " claimed but for b_embedded " +
             condition(*v) +
             (v->order == 1 ? " (the embedded weights sum to " + num(b_embedded.sum()) + ")" : "");
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

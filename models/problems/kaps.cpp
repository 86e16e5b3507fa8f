#include "models/problems/kaps.hpp"

#include <algorithm>
#include <cmath>

namespace stiffbench {

Kaps::Kaps(double eps) : eps_(eps) {
  require_input(std::isfinite(eps) && eps > 0, "kaps: parameter 'eps' must be > 0");
}

void Kaps::eval_rhs(double, CVecRef y, VecRef dydt) const {
  dydt[0] = -(2.0 + 1.0 / eps_) * y[0] + y[1] * y[1] / eps_;
  dydt[1] = y[0] - y[1] - y[1] * y[1];
}

void Kaps::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  const std::vector<Eigen::Triplet<double>> t{{0, 0, -(2.0 + 1.0 / eps_)},
                                              {0, 1, 2.0 * y[1] / eps_},
                                              {1, 0, 1.0},
                                              {1, 1, -1.0 - 2.0 * y[1]}};
  jac.resize(2, 2);
  jac.setFromTriplets(t.begin(), t.end());
}

void Kaps::eval_rhs_explicit_part(double, CVecRef y, VecRef fe) const {
  fe[0] = -2.0 * y[0];
  fe[1] = y[0] - y[1] - y[1] * y[1];
}

void Kaps::eval_rhs_implicit_part(double, CVecRef y, VecRef fi) const {
  fi[0] = (y[1] * y[1] - y[0]) / eps_;
  fi[1] = 0.0;
}

void Kaps::eval_implicit_part_jacobian(double, CVecRef y, SparseMat& jac) const {
  // Fixed pattern: the first row only.
  const std::vector<Eigen::Triplet<double>> t{{0, 0, -1.0 / eps_}, {0, 1, 2.0 * y[1] / eps_}};
  jac.resize(2, 2);
  jac.setFromTriplets(t.begin(), t.end());
}

std::optional<SplitInfo> Kaps::imex_split() const {
  return SplitInfo{"stiff", "the non-stiff terms (-2 y1, y1 - y2 - y2²)",
                   "the 1/ε terms ((y2² - y1)/ε, 0)"};
}

std::optional<SpectrumEstimate> Kaps::explicit_part_spectrum(double, CVecRef y) const {
  // ∂f_E/∂y = [[-2, 0], [1, -1 - 2 y2]] is triangular: eigenvalues -2 and -1 - 2 y2.
  return SpectrumEstimate{std::max(2.0, std::abs(1.0 + 2.0 * y[1])),
                          SpectrumEstimate::Ray::negative_real};
}

void Kaps::exact(double t, VecRef y) const {
  y[0] = std::exp(-2.0 * t);
  y[1] = std::exp(-t);
}

std::optional<double> Kaps::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

}  // namespace stiffbench

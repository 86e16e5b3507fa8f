#include "models/problems/kaps.hpp"
#include "models/problems/problem_entry.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

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

// The spectral radius of the 2×2 Jacobian in closed form: λ = tr/2 ± sqrt(tr²/4 - det).
std::optional<double> Kaps::stiffness(double, CVecRef y) const {
  const double a = -(2.0 + 1.0 / eps_), b = 2.0 * y[1] / eps_, c = 1.0, d = -1.0 - 2.0 * y[1];
  const double half_trace = 0.5 * (a + d), det = a * d - b * c;
  const std::complex<double> root = std::sqrt(std::complex<double>(half_trace * half_trace - det));
  return std::max(std::abs(half_trace + root), std::abs(half_trace - root));
}

ModelRegistry::Entry kaps_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info = {.name = "kaps",
               .description =
                   "Kaps' problem y1' = -(2 + 1/ε) y1 + y2²/ε, y2' = y1 - y2 - y2², exact "
                   "(e^{-2t}, e^{-t}) for every ε; split=stiff: the 1/ε terms implicit; end time 1",
               .exact = true,
               .source = "Kaps & Rentrop, Numer. Math. 33 (1979); Hairer & Wanner II §IV.15 (order "
                         "reduction)",
               .size = fixed_problem_size},
      .params = {{"eps", P::real, "1e-6", "stiffness parameter ε", B::positive()},
                 {"split",
                  P::text,
                  "stiff",
                  "additive split f = f_E + f_I: stiff (f_I = the 1/ε terms, f_E the rest)",
                  {"stiff"}}},
      .make = [](const Params& p) {
        p.text("split");  // one split (stiff): nothing to choose
        return std::make_unique<Kaps>(p.real("eps"));
      }};
}

}  // namespace stiffbench

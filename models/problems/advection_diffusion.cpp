#include "models/problems/advection_diffusion.hpp"
#include "models/problems/problem_entry.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

namespace stiffbench {

AdvectionDiffusion::AdvectionDiffusion(int n, double a, double nu, double r, int k)
    : n_(n), a_(a), nu_(nu), r_(r), k_(k) {
  require_input(n >= 3, "advection_diffusion: parameter 'n' must be >= 3");
  require_input(std::isfinite(a), "advection_diffusion: parameter 'a' must be finite");
  require_input(std::isfinite(nu) && nu >= 0, "advection_diffusion: parameter 'nu' must be >= 0");
  require_input(std::isfinite(r) && r >= 0, "advection_diffusion: parameter 'r' must be >= 0");
  require_input(k >= 0, "advection_diffusion: parameter 'k' must be >= 0");
  const double pi = std::numbers::pi;
  dx_ = 1.0 / n;
  theta_ = 2.0 * pi * k / n;
  const double s = std::sin(theta_ / 2.0);
  mu_ = -r_ - 4.0 * nu_ / (dx_ * dx_) * s * s;
  omega_ = a_ / dx_ * std::sin(theta_);
  rho_ = 0.0;
  double max_sin = 0.0;
  for (int m = 0; m < n_; ++m) {
    const double th = 2.0 * pi * m / n_;
    const double sh = std::sin(th / 2.0);
    const std::complex<double> lambda(-r_ - 4.0 * nu_ / (dx_ * dx_) * sh * sh,
                                      -a_ / dx_ * std::sin(th));
    rho_ = std::max(rho_, std::abs(lambda));
    max_sin = std::max(max_sin, std::abs(std::sin(th)));
  }
  advection_radius_ = std::abs(a_) / dx_ * max_sin;
}

Vec AdvectionDiffusion::initial_state() const {
  Vec u(n_);
  for (int j = 0; j < n_; ++j) u[j] = std::sin(theta_ * j);
  return u;
}

void AdvectionDiffusion::exact(double t, VecRef y) const {
  const double amp = std::exp(mu_ * t);
  for (int j = 0; j < n_; ++j) y[j] = amp * std::sin(theta_ * j - omega_ * t);
}

void AdvectionDiffusion::eval_rhs(double, CVecRef y, VecRef dydt) const {
  const double ca = a_ / (2.0 * dx_), cd = nu_ / (dx_ * dx_);
  for (int j = 0; j < n_; ++j) {
    const double left = y[j == 0 ? n_ - 1 : j - 1], right = y[j == n_ - 1 ? 0 : j + 1];
    dydt[j] = -ca * (right - left) + cd * (right - 2.0 * y[j] + left) - r_ * y[j];
  }
}

void AdvectionDiffusion::eval_rhs_explicit_part(double, CVecRef y, VecRef fe) const {
  const double ca = a_ / (2.0 * dx_);
  for (int j = 0; j < n_; ++j) {
    const double left = y[j == 0 ? n_ - 1 : j - 1], right = y[j == n_ - 1 ? 0 : j + 1];
    fe[j] = -ca * (right - left);
  }
}

void AdvectionDiffusion::eval_rhs_implicit_part(double, CVecRef y, VecRef fi) const {
  const double cd = nu_ / (dx_ * dx_);
  for (int j = 0; j < n_; ++j) {
    const double left = y[j == 0 ? n_ - 1 : j - 1], right = y[j == n_ - 1 ? 0 : j + 1];
    fi[j] = cd * (right - 2.0 * y[j] + left) - r_ * y[j];
  }
}

void AdvectionDiffusion::tridiagonal(double lower, double diag, double upper,
                                     SparseMat& jac) const {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(3 * n_));
  for (int j = 0; j < n_; ++j) {
    t.emplace_back(j, j == 0 ? n_ - 1 : j - 1, lower);
    t.emplace_back(j, j, diag);
    t.emplace_back(j, j == n_ - 1 ? 0 : j + 1, upper);
  }
  jac.resize(n_, n_);
  jac.setFromTriplets(t.begin(), t.end());
}

void AdvectionDiffusion::eval_jacobian(double, CVecRef, SparseMat& jac) const {
  const double ca = a_ / (2.0 * dx_), cd = nu_ / (dx_ * dx_);
  tridiagonal(ca + cd, -2.0 * cd - r_, -ca + cd, jac);
}

void AdvectionDiffusion::eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const {
  const double cd = nu_ / (dx_ * dx_);
  tridiagonal(cd, -2.0 * cd - r_, cd, jac);
}

std::optional<SplitInfo> AdvectionDiffusion::imex_split() const {
  return SplitInfo{"advection", "advection -a u_x (central differences)",
                   "diffusion and reaction ν u_xx - r u"};
}

ModelRegistry::Entry advection_diffusion_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info =
          {.name = "advection_diffusion",
           .description =
               "1D periodic u_t + a u_x = ν u_xx - r u on [0,1), central differences on n cells, "
               "initial sin(2πk x); split=advection: advection explicit, diffusion and reaction "
               "implicit; end time 1",
           .exact = true,
           .source =
               "method of lines; exact solution of the ODE e^{μt} sin(θj - ωt) from the circulant "
               "operator's Fourier modes",
           // advection_diffusion: n unknowns, the tridiagonal Jacobian (3n nonzeros of 12 bytes).
           .size =
               [](const Params& p) {
                 const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                 return ModelSize{n, 12.0 * 3.0 * n + 32.0 * n, 3.0 * n,
                                  "n=" + std::to_string(p.integer("n"))};
               }},
      .params = {{"n", P::integer, "256", "cells N (Δx = 1/N)", B::in(3, 10000000)},
                 {"a", P::real, "1", "advection speed a", B::any()},
                 {"nu", P::real, "1e-4", "diffusion coefficient ν", B::non_negative()},
                 {"r", P::real, "0", "reaction (decay) rate r", B::non_negative()},
                 {"k", P::integer, "1", "wave number of the initial mode sin(2πk x)",
                  B::in(0, 1e9)},
                 {"split",
                  P::text,
                  "advection",
                  "additive split f = f_E + f_I: advection (advection explicit; diffusion and "
                  "reaction implicit)",
                  {"advection"}}},
      .make = [](const Params& p) {
        p.text("split");  // one split (advection): nothing to choose
        return std::make_unique<AdvectionDiffusion>(static_cast<int>(p.integer("n")), p.real("a"),
                                                    p.real("nu"), p.real("r"),
                                                    static_cast<int>(p.integer("k")));
      }};
}

}  // namespace stiffbench

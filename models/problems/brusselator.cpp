#include "models/problems/brusselator.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace stiffbench {

namespace {
constexpr double kUBoundary = 1.0;  // u_0 = u_{N+1}
constexpr double kVBoundary = 3.0;  // v_0 = v_{N+1}
}  // namespace

Brusselator::Brusselator(int n, double alpha) : n_(n), alpha_(alpha) {
  require_input(n >= 1, "brusselator: parameter 'n' must be >= 1");
  require_input(std::isfinite(alpha) && alpha > 0, "brusselator: parameter 'alpha' must be > 0");
  const double np1 = n_ + 1.0;
  c_ = alpha_ * np1 * np1;
}

Vec Brusselator::initial_state() const {
  Vec y(2 * n_);
  for (int i = 1; i <= n_; ++i) {
    const double x = i / (n_ + 1.0);
    y[2 * (i - 1)] = 1.0 + std::sin(2.0 * std::numbers::pi * x);
    y[2 * (i - 1) + 1] = 3.0;
  }
  return y;
}

void Brusselator::eval_rhs(double, CVecRef y, VecRef f) const {
  for (int k = 0; k < n_; ++k) {
    const double u = y[2 * k], v = y[2 * k + 1];
    const double ul = k == 0 ? kUBoundary : y[2 * k - 2];
    const double vl = k == 0 ? kVBoundary : y[2 * k - 1];
    const double ur = k == n_ - 1 ? kUBoundary : y[2 * k + 2];
    const double vr = k == n_ - 1 ? kVBoundary : y[2 * k + 3];
    const double uuv = u * u * v;
    f[2 * k] = 1.0 + uuv - 4.0 * u + c_ * (ul - 2.0 * u + ur);
    f[2 * k + 1] = 3.0 * u - uuv + c_ * (vl - 2.0 * v + vr);
  }
}

void Brusselator::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(8 * n_));
  for (int k = 0; k < n_; ++k) {
    const int iu = 2 * k, iv = 2 * k + 1;
    const double u = y[iu], v = y[iv];
    if (k > 0) {
      t.emplace_back(iu, iu - 2, c_);
      t.emplace_back(iv, iv - 2, c_);
    }
    t.emplace_back(iu, iu, 2.0 * u * v - 4.0 - 2.0 * c_);
    t.emplace_back(iu, iv, u * u);
    t.emplace_back(iv, iu, 3.0 - 2.0 * u * v);
    t.emplace_back(iv, iv, -u * u - 2.0 * c_);
    if (k < n_ - 1) {
      t.emplace_back(iu, iu + 2, c_);
      t.emplace_back(iv, iv + 2, c_);
    }
  }
  jac.resize(2 * n_, 2 * n_);
  jac.setFromTriplets(t.begin(), t.end());
}

std::optional<double> Brusselator::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

std::string Brusselator::component_name(Index i) const {
  if (i < 0 || i >= dimension()) return {};
  return (i % 2 == 0 ? "u_" : "v_") + std::to_string(i / 2 + 1);
}

std::vector<Profile> Brusselator::profiles(double, CVecRef y) const {
  Profile p{"brusselator", {"x", "u", "v"}, {}};
  p.rows.reserve(static_cast<std::size_t>(n_ + 2));
  p.rows.push_back({0.0, kUBoundary, kVBoundary});
  for (int i = 1; i <= n_; ++i)
    p.rows.push_back({i / (n_ + 1.0), y[2 * (i - 1)], y[2 * (i - 1) + 1]});
  p.rows.push_back({1.0, kUBoundary, kVBoundary});
  return {p};
}

ModelRegistry::Entry brusselator_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info =
          {.name = "brusselator",
           .description =
               "1D Brusselator with diffusion: u' = 1 + u²v - 4u + α(N+1)² Δu, v' = 3u - u²v + "
               "α(N+1)² Δv on N interior points, u = 1, v = 3 at both ends, u(0) = 1 + sin(2πx), "
               "v(0) = 3; unknowns interleaved (banded Jacobian); end time 10",
           .source =
               "Hairer, Nørsett & Wanner I §I.16; Hairer & Wanner II §IV.1 (BRUSS, N = 500 in "
               "§IV.10)",
           // brusselator: 2n unknowns, the banded Jacobian (8n - 4 nonzeros of 12 bytes).
           .size =
               [](const Params& p) {
                 const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                 return ModelSize{2.0 * n, 12.0 * 8.0 * n + 64.0 * n, 8.0 * n,
                                  "n=" + std::to_string(p.integer("n"))};
               }},
      .params = {{"n", P::integer, "32", "interior grid points N (x_i = i/(N+1); 2N unknowns)",
                  B::in(1, 10000000)},
                 {"alpha", P::real, "0.02", "diffusion coefficient α (1/50 in the literature)",
                  B::positive()}},
      .make = [](const Params& p) {
        return std::make_unique<Brusselator>(static_cast<int>(p.integer("n")), p.real("alpha"));
      }};
}

}  // namespace stiffbench

#include "models/problems/brusselator.hpp"

#include <cmath>
#include <numbers>

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

std::vector<Profile> Brusselator::profiles(double, CVecRef y) const {
  Profile p{"brusselator", {"x", "u", "v"}, {}};
  p.rows.reserve(static_cast<std::size_t>(n_ + 2));
  p.rows.push_back({0.0, kUBoundary, kVBoundary});
  for (int i = 1; i <= n_; ++i)
    p.rows.push_back({i / (n_ + 1.0), y[2 * (i - 1)], y[2 * (i - 1) + 1]});
  p.rows.push_back({1.0, kUBoundary, kVBoundary});
  return {p};
}

}  // namespace stiffbench

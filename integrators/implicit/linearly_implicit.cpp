#include "integrators/implicit/linearly_implicit.hpp"

#include <cmath>

namespace stiffbench {

SemiImplicitEuler::SemiImplicitEuler(ImplicitOptions opt)
    : Integrator({"semi_implicit_euler",
                  Family::implicit,
                  1,
                  1,
                  {},
                  "linearly implicit Euler (I - hJ) dy = h f(t, y): one linear solve, no Newton"}),
      core_(std::move(opt)) {}

void SemiImplicitEuler::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  for (Vec* v : {&f_, &dy_, &ft_, &rhs_}) v->resize(sys.dimension());
}

Status SemiImplicitEuler::step(const OdeSystem& sys, double t, VecRef y, double h,
                               SolveStats& stats) {
  sys.rhs(t, y, f_);
  core_.update_jacobian(sys, t, y, f_, stats);
  if (!core_.prepare(h, stats)) {
    stats.message = "singular matrix I - hJ at t = " + std::to_string(t);
    return Status::solver_error;
  }
  // Non-autonomous f: the method applied to the autonomised system (t' = 1) adds h² f_t, so a
  // stiff forced problem tracks its slow solution (without it y⁺ lags φ by h φ').
  rhs_ = h * f_;
  if (!sys.autonomous()) {
    const double dt = 1.4901161193847656e-08 * std::max(1.0, std::abs(t));
    sys.rhs(t + dt, y, ft_);
    rhs_.noalias() += (h * h / dt) * (ft_ - f_);
  }
  dy_.setZero();
  if (!core_.solve(rhs_, dy_, stats)) {
    stats.message = "linear solve failed at t = " + std::to_string(t);
    return Status::solver_error;
  }
  y += dy_;
  return Status::ok;
}

const RosenbrockTableau& rosenbrock2_tableau() {
  static const RosenbrockTableau tab = [] {
    RosenbrockTableau r;
    r.name = "rosenbrock2";
    r.order = 2;
    r.gamma = 1.0 + 1.0 / std::sqrt(2.0);
    r.alpha = Mat{{0.0, 0.0}, {1.0, 0.0}};
    r.gamma_lower = Mat{{0.0, 0.0}, {-2.0 * r.gamma, 0.0}};
    r.b = Vec{{0.5, 0.5}};
    return r;
  }();
  return tab;
}

Rosenbrock::Rosenbrock(RosenbrockTableau tableau, std::string description, ImplicitOptions opt)
    : Integrator({tableau.name,
                  Family::implicit,
                  tableau.order,
                  static_cast<int>(tableau.b.size()),
                  {},
                  std::move(description)}),
      tab_(std::move(tableau)),
      core_(std::move(opt)) {}

void Rosenbrock::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  const Index n = sys.dimension();
  k_.resize(n, tab_.b.size());
  for (Vec* v : {&u_, &f_, &ft_, &rhs_, &sum_, &jv_}) v->resize(n);
}

Status Rosenbrock::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  const Index s = tab_.b.size();
  sys.rhs(t, y, f_);
  core_.update_jacobian(sys, t, y, f_, stats);
  if (!core_.prepare(h * tab_.gamma, stats)) {
    stats.message = "singular matrix I - hγJ at t = " + std::to_string(t);
    return Status::solver_error;
  }
  const bool need_ft = !sys.autonomous();
  if (need_ft) {
    const double dt = 1.4901161193847656e-08 * std::max(1.0, std::abs(t));
    sys.rhs(t + dt, y, ft_);
    ft_ = (ft_ - f_) / dt;
  }
  for (Index i = 0; i < s; ++i) {
    double alpha_i = 0, gamma_i = tab_.gamma;
    u_ = y;
    sum_.setZero();
    for (Index j = 0; j < i; ++j) {
      alpha_i += tab_.alpha(i, j);
      gamma_i += tab_.gamma_lower(i, j);
      if (tab_.alpha(i, j) != 0.0) u_.noalias() += tab_.alpha(i, j) * k_.col(j);
      if (tab_.gamma_lower(i, j) != 0.0) sum_.noalias() += tab_.gamma_lower(i, j) * k_.col(j);
    }
    if (i == 0) {
      rhs_ = h * f_;  // stage 1 is evaluated at (t, y): reuse f(t, y)
    } else {
      sys.rhs(t + alpha_i * h, u_, rhs_);
      rhs_ *= h;
    }
    if (need_ft) rhs_.noalias() += (gamma_i * h * h) * ft_;
    if (i > 0) {
      core_.jacobian_times(sum_, jv_, stats);
      rhs_.noalias() += h * jv_;
    }
    auto ki = k_.col(i);
    ki.setZero();
    if (!core_.solve(rhs_, ki, stats)) {
      stats.message = "linear solve failed at t = " + std::to_string(t);
      return Status::solver_error;
    }
  }
  for (Index i = 0; i < s; ++i) y.noalias() += tab_.b[i] * k_.col(i);
  return Status::ok;
}

}  // namespace stiffbench

#include "integrators/implicit/dirk.hpp"

#include <cmath>

namespace stiffbench {

namespace {

ButcherTableau make(std::string name, int order, Mat a, Vec b) {
  ButcherTableau t;
  t.name = std::move(name);
  t.order = order;
  t.c = a.rowwise().sum();
  t.a = std::move(a);
  t.b = std::move(b);
  return t;
}

std::vector<ButcherTableau> build() {
  std::vector<ButcherTableau> all;
  all.push_back(make("backward_euler", 1, Mat::Constant(1, 1, 1.0), Vec::Constant(1, 1.0)));
  all.push_back(make("implicit_midpoint", 2, Mat::Constant(1, 1, 0.5), Vec::Constant(1, 1.0)));
  all.push_back(make("trapezoidal", 2, Mat{{0.0, 0.0}, {0.5, 0.5}}, Vec{{0.5, 0.5}}));
  {
    const double g = 1.0 - 1.0 / std::sqrt(2.0);
    all.push_back(make("sdirk2", 2, Mat{{g, 0.0}, {1.0 - g, g}}, Vec{{1.0 - g, g}}));
  }
  {
    // Alexander (1977), SIAM J. Numer. Anal. 14; Hairer–Wanner II Table IV.6.5.
    const double g = 0.43586652150845899941601945;
    const double tau = (1.0 + g) / 2.0;
    const double b1 = -(6 * g * g - 16 * g + 1) / 4.0;
    const double b2 = (6 * g * g - 20 * g + 5) / 4.0;
    all.push_back(
        make("sdirk3", 3, Mat{{g, 0.0, 0.0}, {tau - g, g, 0.0}, {b1, b2, g}}, Vec{{b1, b2, g}}));
  }
  return all;
}

}  // namespace

const std::vector<ButcherTableau>& implicit_tableaux() {
  static const std::vector<ButcherTableau> all = build();
  return all;
}

const ButcherTableau& implicit_tableau(const std::string& name) {
  for (const auto& t : implicit_tableaux())
    if (t.name == name) return t;
  throw std::logic_error("no implicit tableau '" + name + "'");
}

void DirkStepper::reset(Index n) {
  k_.resize(n, tableau_.stages());
  psi_.resize(n);
  z_.resize(n);
  fz_.resize(n);
}

Status DirkStepper::step(ImplicitCore& core, const OdeSystem& sys, double t, VecRef y, double h,
                         SolveStats& stats) {
  const int s = tableau_.stages();
  core.new_step();
  z_ = y;  // predictor for the first implicit stage; later stages start from the previous z
  for (int i = 0; i < s; ++i) {
    psi_ = y;
    for (int j = 0; j < i; ++j)
      if (const double aij = tableau_.a(i, j); aij != 0.0) psi_.noalias() += (h * aij) * k_.col(j);
    const double ti = t + tableau_.c[i] * h;
    const double aii = tableau_.a(i, i);
    if (aii == 0.0) {
      sys.rhs(ti, psi_, k_.col(i));
      z_ = psi_;
      continue;
    }
    const Status st = core.solve_stage(sys, ti, psi_, h * aii, z_, fz_, stats);
    if (st != Status::ok) return st;
    // k_i from the stage equation rather than f(z_i): the Newton error in z_i is not amplified
    // by a stiff Jacobian, and a stiffly accurate method returns y⁺ = z_s (Hairer–Wanner IV.8).
    k_.col(i) = (z_ - psi_) / (h * aii);
  }
  for (int i = 0; i < s; ++i)
    if (const double bi = tableau_.b[i]; bi != 0.0) y.noalias() += (h * bi) * k_.col(i);
  return Status::ok;
}

DirkIntegrator::DirkIntegrator(ButcherTableau tableau, std::string description, ImplicitOptions opt)
    : Integrator({tableau.name,
                  Family::implicit,
                  tableau.order,
                  tableau.stages(),
                  {},
                  std::move(description)}),
      stepper_(std::move(tableau)),
      core_(std::move(opt)) {}

void DirkIntegrator::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  stepper_.reset(sys.dimension());
}

Status DirkIntegrator::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  return stepper_.step(core_, sys, t, y, h, stats);
}

Bdf2Integrator::Bdf2Integrator(ImplicitOptions opt)
    : Integrator({"bdf2",
                  Family::implicit,
                  2,
                  1,
                  {},
                  "two-step backward differentiation formula; sdirk2 start-up step"}),
      core_(std::move(opt)),
      startup_(implicit_tableau("sdirk2")) {}

void Bdf2Integrator::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  const Index n = sys.dimension();
  startup_.reset(n);
  y_prev_.resize(n);
  y_last_.resize(n);
  psi_.resize(n);
  z_.resize(n);
  fz_.resize(n);
  started_ = false;
}

Status Bdf2Integrator::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  if (!started_ || h != h_last_ || y != y_last_) {
    y_prev_ = y;
    const Status st = startup_.step(core_, sys, t, y, h, stats);
    if (st != Status::ok) return st;
  } else {
    core_.new_step();
    psi_ = (4.0 / 3.0) * y - (1.0 / 3.0) * y_prev_;
    z_ = 2.0 * y - y_prev_;
    const Status st = core_.solve_stage(sys, t + h, psi_, (2.0 / 3.0) * h, z_, fz_, stats);
    if (st != Status::ok) return st;
    y_prev_ = y;
    y = z_;
  }
  y_last_ = y;
  h_last_ = h;
  started_ = true;
  return Status::ok;
}

}  // namespace stiffbench

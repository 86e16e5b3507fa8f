#include "models/problems/prothero_robinson.hpp"

#include <cmath>

namespace stiffbench {

double ProtheroRobinson::phi(double t) const {
  switch (phi_) {
    case Phi::sin:
      return std::sin(t);
    case Phi::cos:
      return std::cos(t);
    case Phi::exp:
      return std::exp(t);
  }
  return 0;
}

double ProtheroRobinson::phi_dot(double t) const {
  switch (phi_) {
    case Phi::sin:
      return std::cos(t);
    case Phi::cos:
      return -std::sin(t);
    case Phi::exp:
      return std::exp(t);
  }
  return 0;
}

void ProtheroRobinson::eval_rhs(double t, CVecRef y, VecRef dydt) const {
  dydt[0] = lambda_ * (y[0] - phi(t)) + phi_dot(t);
}

void ProtheroRobinson::eval_jacobian(double, CVecRef, SparseMat& jac) const {
  jac.resize(1, 1);
  jac.setZero();
  jac.insert(0, 0) = lambda_;
}

std::optional<SplitInfo> ProtheroRobinson::imex_split() const {
  return SplitInfo{"stiff", "φ'(t) (independent of y)", "λ(y - φ(t)) (the stiff term)"};
}

void ProtheroRobinson::exact(double t, VecRef y) const {
  y[0] = phi(t) + offset_ * std::exp(lambda_ * t);
}

}  // namespace stiffbench
